"""The README's code runs as written: its Python blocks in order, as a reader would paste them into one
session; a block that starts with ``# <name>.py`` is a file the reader saves, and the ``subenv``
command that uses it runs in a process of its own, as a reader would type it."""

from __future__ import annotations

import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from subenv.evaluation import controller as controller_module

README = Path(__file__).resolve().parents[1] / "README.md"
TEXT = README.read_text("utf-8")
BLOCKS = re.findall(r"```python\n(.*?)```", TEXT, flags=re.DOTALL)
FILES = {m.group(1): block for block in BLOCKS if (m := re.match(r"# (\w+\.py)\n", block))}
PLUGIN_COMMANDS = [
    line
    for block in re.findall(r"```bash\n(.*?)```", TEXT, flags=re.DOTALL)
    for line in block.splitlines()
    if line.startswith("subenv evaluate --plugins")
]


def _leaderboard_row(printed: str, name: str) -> dict[str, str]:
    header = next(line for line in printed.splitlines() if line.startswith("| controller |"))
    row = next(line for line in printed.splitlines() if line.startswith(f"| {name} |"))
    return dict(zip((c.strip() for c in header.split("|")), (c.strip() for c in row.split("|")), strict=True))


def test_the_readme_has_its_examples() -> None:
    assert len(BLOCKS) >= 5 and "class DepthP" in FILES.get("depth_p.py", "") and len(PLUGIN_COMMANDS) == 1


def test_every_python_block_of_the_readme_runs(tmp_path, monkeypatch, capsys) -> None:
    pytest.importorskip("stable_baselines3")  # (the agents' and SB3's blocks need the "rl" extra)
    monkeypatch.chdir(tmp_path)
    monkeypatch.syspath_prepend(str(tmp_path))
    # What the file registers on import is this test's only.
    monkeypatch.setattr(controller_module, "_REGISTRY", dict(controller_module._REGISTRY))
    monkeypatch.delitem(sys.modules, "depth_p", raising=False)
    namespace: dict[str, object] = {"__name__": "__readme__"}
    try:
        for k, block in enumerate(BLOCKS):
            if block in FILES.values():
                (tmp_path / next(name for name, text in FILES.items() if text == block)).write_text(block)
                continue
            exec(compile(block, f"README.md python block {k}", "exec"), namespace)  # noqa: S102
    finally:
        sys.modules.pop("depth_p", None)
    printed = capsys.readouterr().out
    # The own-controller example's leaderboard, with its three rows.
    assert all(f"| {name} |" in printed for name in ("depth_p", "thesis", "reversal_aware")), printed
    # What the README says of it: it holds depth on LowSpeed and loses it on Nominal.
    columns = _leaderboard_row(printed, "depth_p")
    assert columns["Nominal"].startswith("0% ") and columns["LowSpeed"].startswith("100% "), columns


def test_the_readme_command_runs_your_own_controller(tmp_path) -> None:
    """The command-line route, in a fresh process from the folder holding the file (no PYTHONPATH)."""
    for name, text in FILES.items():
        (tmp_path / name).write_text(text)
    args = shlex.split(PLUGIN_COMMANDS[0])
    assert args[0] == "subenv"
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
