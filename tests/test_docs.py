"""The documentation's code runs as written, and the built site has every page.

Every ``python`` block of the hand-written pages (``docs/**/*.md``, not the generated folders) runs, in
page order, in one namespace per page, from an empty folder, as a reader would paste them into one
session (``tests/test_readme.py`` does the same for the README); a block that starts with
``# <name>.py`` is a file the reader saves. A page whose blocks need an extra names the modules in its
front matter (``test-requires: [stable_baselines3]``), and its test is skipped, naming them, where one
is missing. What a page registers (scenarios, ids, controllers, suites) is undone after it.

The site's test builds it (Sphinx, the ``docs`` extra) with warnings as errors and checks that every
registered id has its page with its sections and its animation.
"""

from __future__ import annotations

import importlib.util
import json
import math
import re
import subprocess
import sys
from pathlib import Path

import gymnasium as gym
import pytest

import subenv
from subenv.envs.dive_plane import DivePlaneEnv
from subenv.evaluation import controller as controller_module
from subenv.evaluation import suites as suites_module
from subenv.scenarios import registry as scenario_registry
from subenv.vehicles import loader

ROOT = Path(__file__).resolve().parents[1]


def _load(name: str, path: Path):  # type: ignore[no-untyped-def]
    """A module of the docs' or benchmarks' tooling, which are not packages, by its path."""
    spec = importlib.util.spec_from_file_location(name, path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


DOCS = ROOT / "docs"
# Generated at build time, or not pages of the site (docs/conf.py's exclude_patterns).
NOT_WRITTEN_HERE = {"_build", "_ext", "environments", "reproduction", "performance", "remus100", "reference"}
PAGES = sorted(p for p in DOCS.rglob("*.md") if not NOT_WRITTEN_HERE & set(p.relative_to(DOCS).parts[:-1]))
SECTIONS = _load("envpages", DOCS / "_ext" / "envpages.py").SECTIONS
"""The environment docstring's sections, which every id's page shows (the generator's list)."""


def _blocks(text: str) -> list[str]:
    return re.findall(r"^```python\n(.*?)^```", text, flags=re.DOTALL | re.MULTILINE)


def _requires(text: str) -> list[str]:
    front = re.match(r"---\n(.*?)\n---\n", text, flags=re.DOTALL)
    found = re.search(r"^test-requires: \[(.*)\]$", front.group(1), flags=re.MULTILINE) if front else None
    return [name.strip() for name in found.group(1).split(",")] if found else []


EXAMPLES = [p for p in PAGES if _blocks(p.read_text("utf-8"))]


def test_the_pages_have_their_examples() -> None:
    names = {p.relative_to(DOCS).as_posix() for p in EXAMPLES}
    assert {"index.md", "guides/controller.md", "guides/training.md", "guides/vehicle.md"} <= names
    assert sum(len(_blocks(p.read_text("utf-8"))) for p in EXAMPLES) >= 25


@pytest.mark.parametrize("page", EXAMPLES, ids=[p.relative_to(DOCS).as_posix() for p in EXAMPLES])
def test_every_python_block_of_the_page_runs(page: Path, tmp_path, monkeypatch, capsys) -> None:
    text = page.read_text("utf-8")
    blocks = _blocks(text)
    missing = [name for name in _requires(text) if importlib.util.find_spec(name) is None]
    if missing:
        pytest.skip(f"{page.name} needs {missing} (its front matter's test-requires: install the extra)")
    monkeypatch.chdir(tmp_path)
    monkeypatch.syspath_prepend(str(tmp_path))
    # What a page registers is its test's only.
    monkeypatch.setattr(controller_module, "_REGISTRY", dict(controller_module._REGISTRY))
    monkeypatch.setattr(suites_module, "_REGISTRY", dict(suites_module._REGISTRY))
    monkeypatch.setattr(scenario_registry, "_REGISTRY", dict(scenario_registry._REGISTRY))
    specs = dict(gym.registry)
    files = {m.group(1): block for block in blocks if (m := re.match(r"# (\w+\.py)\n", block))}
    modules = set(sys.modules)
    namespace: dict[str, object] = {"__name__": f"__docs_{page.stem}__"}
    try:
        for k, block in enumerate(blocks):
            if block in files.values():
                (tmp_path / next(name for name, body in files.items() if body == block)).write_text(block)
                continue
            exec(compile(block, f"{page.relative_to(ROOT)} python block {k}", "exec"), namespace)
    finally:
        for name in set(sys.modules) - modules:
            if name.removesuffix(".py") in {f.removesuffix(".py") for f in files}:
                del sys.modules[name]
        gym.registry.clear()
        gym.registry.update(specs)
    printed = capsys.readouterr().out
    assert printed  # (every page's examples print what they show)
    if page.name == "controller.md":  # what the page says of its controller: dive-plane reversal
        columns = _leaderboard_row(printed, "depth_p")
        assert columns["Nominal"].startswith("0% ") and columns["LowSpeed"].startswith("100% "), columns


def _leaderboard_row(printed: str, name: str) -> dict[str, str]:
    header = next(line for line in printed.splitlines() if line.startswith("| controller |"))
    row = next(line for line in printed.splitlines() if line.startswith(f"| {name} |"))
    return dict(zip((c.strip() for c in header.split("|")), (c.strip() for c in row.split("|")), strict=True))


def test_the_vehicle_guide_names_every_field_of_the_format() -> None:
    table = (
        (DOCS / "guides" / "vehicle.md").read_text("utf-8").split("## The format", 1)[1].split("## ", 1)[0]
    )
    named = set()
    for row in re.findall(r"^\| (.*?) \|", table, flags=re.MULTILINE):
        section = re.match(r"`\[(\w+)\]`", row)
        keys = re.findall(r"`(\w+)`", row.split("]`", 1)[-1])
        named |= {f"{section.group(1)}.{key}" if section else key for key in keys}
    schema = {f"{section}.{key}" for section, keys in loader._SCHEMA.items() for key in keys}
    assert named == schema | set(loader._TOP_LEVEL)


def test_the_env_pages_use_every_section_of_the_docstring() -> None:
    envpages = _load("envpages", DOCS / "_ext" / "envpages.py")
    assert tuple(envpages.docstring_sections(DivePlaneEnv.__doc__ or "")) == SECTIONS


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The site, built with warnings as errors into a temporary folder (the generated pages are written
    once per change of their sources: a build after ``./dev docs`` reuses them)."""
    pytest.importorskip(
        "sphinx", reason="Sphinx is not installed: the 'docs' extra (pip install -e '.[docs]')"
    )
    for module in ("furo", "myst_parser"):
        pytest.importorskip(
            module, reason=f"{module} is not installed: the 'docs' extra (pip install -e '.[docs]')"
        )
    out = tmp_path_factory.mktemp("site")
    done = subprocess.run(
        [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html", str(DOCS), str(out)],
        capture_output=True,
        text=True,
        timeout=3000,
        check=False,
    )
    assert done.returncode == 0, done.stderr[-5000:]
    return out


def test_every_id_has_its_page_with_its_sections_and_animation(site: Path) -> None:
    from PIL import Image

    for env_id in subenv.env_ids():
        name = env_id.split("/", 1)[1]
        html = (site / "environments" / f"{name}.html").read_text("utf-8")
        assert f"<h1>{env_id}" in html
        for section in SECTIONS:
            assert f">{section}<" in html, (env_id, section)
        (src,) = re.findall(r'<img [^>]*src="([^"]+\.gif)"', html)
        with Image.open(site / "environments" / src) as gif:
            assert gif.format == "GIF" and gif.n_frames > 10  # an animation, not a still
        assert f'href="{name}.html"' in (site / "environments" / "index.html").read_text("utf-8")


def test_every_page_was_written_and_every_reference_resolved(site: Path) -> None:
    """Every source page (hand-written or generated) has its HTML page, reachable from the index's
    navigation, and none holds a reference Sphinx could not resolve."""
    sources = [
        p.relative_to(DOCS).with_suffix(".html")
        for p in DOCS.rglob("*.md")
        if not {"_build", "_ext", "remus100", "reference"} & set(p.relative_to(DOCS).parts[:-1])
        and not p.parent.name.endswith(".tmp")
    ]
    assert len(sources) >= len(PAGES) + len(subenv.env_ids())
    assert [p for p in sources if not (site / p).is_file()] == []
    navigation = (site / "index.html").read_text("utf-8")
    for page in sources:
        html = (site / page).read_text("utf-8")
        assert 'class="problematic"' not in html, page
        if page.parent == Path("."):
            assert f'href="{page.as_posix()}"' in navigation or page.name == "index.html", page


def test_the_site_has_the_reproduction_report_and_the_performance_records(site: Path) -> None:
    for vehicle in ("suboff", "remus100"):
        html = (site / "reproduction" / f"{vehicle}.html").read_text("utf-8")
        figures = re.findall(r'<img [^>]*src="([^"]+\.png)"', html)
        assert len(figures) >= 12 and all((site / "reproduction" / src).is_file() for src in figures)
    assert "u_cr, eq. 3.9 closed form" in (site / "reproduction" / "suboff.html").read_text("utf-8")
    speed = (site / "performance" / "speed.html").read_text("utf-8")
    assert "SyncVectorEnv" in speed and re.search(r'<img [^>]*src="[^"]+speed-vector\.png"', speed)


def test_a_benchmark_record_holds_the_tables_it_printed_and_the_docs_read_them(tmp_path, monkeypatch) -> None:
    monkeypatch.syspath_prepend(str(ROOT / "benchmarks"))
    monkeypatch.syspath_prepend(str(DOCS / "_ext"))
    pytest.importorskip("matplotlib", reason="the 'plot' extra is not installed")  # (the pages' figures)
    from _record import write_record
    from performance import number, record_page

    printed = [
        "| environment | N | native env-steps/s |",
        "|---|---:|---:|",
        "| subenv/Nominal-v0 | 64 | 943,727 |",
        "",
    ]
    printed += ["| ceiling | x |", "|---|---:|", "| a | 0.70 |"]
    monkeypatch.setattr(sys, "argv", ["benchmarks/speed.py", "--json", "r.json"])
    write_record(
        tmp_path / "r.json",
        "speed",
        "a machine",
        [("Vector environment", printed)],
        probe_before="1.9x",
        probe_after="1.8x",
    )
    record = json.loads((tmp_path / "r.json").read_text())
    assert (
        record["command"] == "python benchmarks/speed.py --json r.json" and record["machine"] == "a machine"
    )
    (first, second) = record["sections"][0]["tables"]
    assert first == {
        "columns": ["environment", "N", "native env-steps/s"],
        "rows": [["subenv/Nominal-v0", "64", "943,727"]],
    }
    assert second["rows"] == [["a", "0.70"]] and number("943,727") == 943727.0 and math.isnan(number("-"))
    page = record_page(record, tmp_path, "r")
    assert "| subenv/Nominal-v0 | 64 | 943,727 |" in page and "a machine" in page
