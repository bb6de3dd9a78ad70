"""The README is the front door: short, its code runs as written, its links and pictures exist, and its
leaderboard is the benchmark page's. The own-controller example it points at (docs/guides/controller.md)
runs in tests/test_docs.py, and its command-line route here, as a reader would type it."""

from __future__ import annotations

import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import gymnasium as gym

import subenv

ROOT = Path(__file__).resolve().parents[1]
TEXT = (ROOT / "README.md").read_text("utf-8")
BLOCKS = re.findall(r"```python\n(.*?)```", TEXT, flags=re.DOTALL)
GUIDE = (ROOT / "docs" / "guides" / "controller.md").read_text("utf-8")


def _leaderboard_row(printed: str, name: str) -> dict[str, str]:
    header = next(line for line in printed.splitlines() if line.startswith("| controller |"))
    row = next(line for line in printed.splitlines() if line.startswith(f"| {name} |"))
    return dict(zip((c.strip() for c in header.split("|")), (c.strip() for c in row.split("|")), strict=True))


def test_the_readme_is_read_in_two_minutes() -> None:
    assert TEXT.count("\n") <= 200
    # A newcomer reaches a stepping environment from the first screen: the quick start's gym.make.
    assert TEXT.index('gym.make("subenv/') < TEXT.index("## Environments")


def test_every_python_block_of_the_readme_runs(tmp_path, monkeypatch, capsys) -> None:
    assert BLOCKS
    monkeypatch.chdir(tmp_path)
    namespace: dict[str, object] = {"__name__": "__readme__"}
    for k, block in enumerate(BLOCKS):
        exec(compile(block, f"README.md python block {k}", "exec"), namespace)
    assert "m/s, critical 0.578 m/s" in capsys.readouterr().out


def test_the_readme_links_and_pictures_exist() -> None:
    targets = re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", TEXT)
    local = [t for t in targets if not re.match(r"[a-z]+://", t)]
    assert "docs/readme/lowspeed.gif" in local and "docs/readme/reversal.png" in local
    assert [t for t in local if not (ROOT / t).exists()] == []


def test_the_readme_lists_every_registered_id() -> None:
    listed = re.findall(r"^\| `(subenv/[\w-]+)` \|", TEXT, flags=re.MULTILINE)
    assert sorted(listed) == sorted(subenv.env_ids())
    assert all(env_id in gym.registry for env_id in listed)


def test_the_readme_leaderboards_are_the_top_of_the_docs_tables() -> None:
    rows = [line for line in TEXT.splitlines() if line.startswith("| ") and "% [" in line]
    default = [line for line in rows if not line.startswith("| hard ")]
    table = [
        line
        for line in (ROOT / "docs" / "benchmark.md").read_text("utf-8").splitlines()
        if line.startswith("| ") and "% [" in line
    ]
    assert len(default) >= 3 and default == table[: len(default)]
    # The Hard track's top rows, as the reporting guide's reference results give them, in its order.
    hard = [line for line in rows if line.startswith("| hard ")]
    reference = (ROOT / "docs" / "guides" / "reporting.md").read_text("utf-8").splitlines()
    assert len(hard) >= 3 and hard == [line for line in reference if line.startswith("| hard ")][: len(hard)]


def test_the_guide_command_runs_your_own_controller(tmp_path) -> None:
    """The command-line route of the own-controller guide, in a fresh process from the folder holding the
    file (no PYTHONPATH), as the README sends a reader there."""
    (tmp_path / "depth_p.py").write_text(GUIDE.split("```python\n# depth_p.py\n", 1)[1].split("```", 1)[0])
    (command_line,) = [line for line in GUIDE.splitlines() if line.startswith("subenv evaluate --plugins")]
    args = shlex.split(command_line)
    # The installed console script (whose path, unlike `python -m`'s, does not hold the current directory).
    script = shutil.which("subenv", path=str(Path(sys.executable).parent))
    command = [script] if script else [sys.executable, "-m", "subenv"]
    done = subprocess.run(
        [*command, *args[1:], "--no-progress", "--no-plots"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    columns = _leaderboard_row(done.stdout, "depth_p")
    assert columns["Nominal"].startswith("0% ") and columns["LowSpeed"].startswith("100% "), done.stdout
    assert (tmp_path / "my-comparison" / "leaderboard.md").is_file()
