"""The wheel: what it holds, and what a user gets who installs it into a clean venv outside the clone.

The environments, the classical controllers and the shipped agents (found through the
``subenv.controllers`` entry points), the SPDX license, and one-line messages for the extras that
are not installed (matplotlib for plots, Stable-Baselines3 for the agents).
"""

from __future__ import annotations

import csv
import os
import shutil
import subprocess
import sys
import venv
import zipfile
from pathlib import Path

import pytest

import subenv_baselines
from subenv.evaluation import ENTRY_POINT_GROUP
from subenv_agents import shipped_models

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib  # type: ignore[no-redef]

ROOT = Path(__file__).resolve().parents[1]


def test_every_controller_is_declared_as_an_entry_point():
    """pyproject.toml declares each classical controller and each shipped model, by its name (the JAX
    PPO's folder has its own loader)."""
    declared = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["entry-points"][
        ENTRY_POINT_GROUP
    ]
    expected = {
        name: f"{cls.__module__}:{cls.__qualname__}" for name, cls in subenv_baselines.CONTROLLERS.items()
    }
    expected |= subenv_baselines.OPTIONAL_CONTROLLERS
    expected |= {name: f"subenv_agents.shipped:{name}" for name in shipped_models()}
    expected["ppo_jax"] = "subenv_agents.jax_ppo:shipped"
    assert declared == expected


def _run(*command: str | Path, cwd: Path, ok: bool = True) -> subprocess.CompletedProcess[str]:
    # Without PYTHONPATH: set (to a checkout) where the suite runs, it would put the checkout before the
    # clean venv's site-packages.
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    done = subprocess.run(
        [str(c) for c in command], check=False, capture_output=True, text=True, cwd=cwd, env=env
    )
    assert (done.returncode == 0) == ok, (done.returncode, done.stdout, done.stderr)
    return done


@pytest.mark.wheel
def test_wheel_installs_into_a_clean_venv_and_evaluates(tmp_path: Path):
    # Built from a copy of what the build reads (a few MB): setuptools writes build/ and subenv.egg-info/
    # beside the sources, and in the checkout that would rewrite the metadata that other tests' processes
    # read while they run (pytest-xdist), and could put a stale build/ in the wheel.
    source = tmp_path / "source"
    source.mkdir()
    pyproject = tomllib.loads((ROOT / "pyproject.toml").read_text())
    for name in ("pyproject.toml", pyproject["project"]["readme"], *pyproject["project"]["license-files"]):
        shutil.copy2(ROOT / name, source / name)
    for package in {
        name.split(".")[0] for name in pyproject["tool"]["setuptools"]["packages"]["find"]["include"]
    }:
        shutil.copytree(ROOT / package, source / package, ignore=shutil.ignore_patterns("__pycache__"))
    dist = tmp_path / "dist"
    _run(
        sys.executable,
        "-m",
        "pip",
        "wheel",
        "--no-deps",
        "--no-build-isolation",
        "-q",
        "-w",
        dist,
        source,
        cwd=tmp_path,
    )
    (wheel,) = dist.glob("subenv-*.whl")
    archive = zipfile.ZipFile(wheel)
    names = archive.namelist()
    for name in (
        "subenv/vehicles/data/suboff.toml",
        "subenv/evaluation/data/achievable-hard.json",
        "subenv/py.typed",
        "subenv_baselines/thesis.py",
        "subenv_agents/shipped.py",
        "subenv_agents/hyperparams/ppo.yml",
        "subenv_agents/models/ppo/model.zip",
        "subenv_agents/models/sac/vecnormalize.pkl",
        "subenv_agents/models/ppo_jax/network.npz",
        "subenv_agents/jax_ppo.py",
        "subenv/jax/env.py",
        "subenv-0.2.0.dist-info/licenses/LICENSE",
    ):
        assert name in names, name
    assert not any(n.startswith(("tests/", "benchmarks/", "baselines/", "agents/")) for n in names)
    metadata = archive.read("subenv-0.2.0.dist-info/METADATA").decode()
    assert "License-Expression: MIT" in metadata.splitlines()

    env_dir = tmp_path / "venv"
    venv.EnvBuilder(with_pip=False).create(env_dir)  # (this pip installs into it: --python; 3 s less)
    python, subenv = env_dir / "bin" / "python", env_dir / "bin" / "subenv"
    # No extras (compiled, as a user gets it).
    _run(sys.executable, "-m", "pip", "--python", python, "install", "-q", wheel, cwd=tmp_path)
    code = (
        "import gymnasium as gym, subenv, pathlib\n"
        "assert 'site-packages' in pathlib.Path(subenv.__file__).as_posix()\n"
        "env = gym.make('subenv/DivePlane-v0')\n"
        "obs, info = env.reset(seed=0)\n"
        "obs, r, te, tr, info = env.step(env.action_space.sample())\n"
        "print(obs.shape, round(info['critical_speed_mps'], 3) > 0)\n"
    )
    assert _run(python, "-c", code, cwd=tmp_path).stdout.strip() == "(8,) True"

    listed = _run(subenv, "evaluate", "--list", cwd=tmp_path)
    controllers = listed.stdout.splitlines()[0].removeprefix("controllers: ").split(", ")
    assert sorted(controllers) == sorted(
        subenv_baselines.CONTROLLERS
    )  # without the extras: no agents, no MPC
    skipped = listed.stderr.splitlines()
    assert len(skipped) == 3
    assert skipped[0].startswith(
        "(skipped mpc: the 'mpc' extra is needed for the MPC baseline (subenv_baselines.mpc): "
        'pip install "subenv[mpc]" (or pip install "daqp>=0.11"; '
    )
    assert skipped[1].startswith(
        "(skipped ppo, sac: the 'rl' extra is needed for the shipped agents: "
        'pip install "subenv[rl]" (or pip install "stable-baselines3>=2.3" '
    )
    assert skipped[2].startswith(
        "(skipped ppo_jax: the 'jax-rl' extra is needed for PPO on the JAX environment "
        '(subenv_agents.jax_ppo): pip install "subenv[jax-rl]" (or pip install "jax>=0.4.30" '
        '"optax>=0.2"; '
    )

    refused = _run(python, "-c", "import subenv.jax", cwd=tmp_path, ok=False)  # jax is not installed
    assert (
        refused.stderr.strip()
        .splitlines()[-1]
        .startswith(
            "subenv.extras.MissingExtra: the 'jax' extra is needed for the physics on JAX (subenv.jax): "
            'pip install "subenv[jax]" (or pip install "jax>=0.4.30"; '
        )
    )

    out = tmp_path / "evaluation"
    evaluate = (
        "evaluate",
        "--suite",
        "tiny",
        "--episodes",
        "1",
        "--controllers",
        "thesis",
        "--no-progress",
        "--out",
        out,
    )
    # matplotlib is not installed: the main job runs, without its plots, and says so in one line.
    bare = _run(subenv, *evaluate, cwd=tmp_path)
    assert (
        "(skipped the plots: the 'plot' extra is needed for the plots: "
        'pip install "subenv[plot]" (or pip install "matplotlib>=3.7"; '
    ) in bare.stderr
    assert not list(out.rglob("*.png"))
    rows = list(csv.DictReader((out / "results.csv").open()))
    assert [row["controller"] for row in rows] == [
        "thesis",
        "thesis",
    ]  # the tiny suite: two scenarios, one episode

    # The own-controller guide's controller, saved beside the user and run from the wheel's command.
    guide = (ROOT / "docs" / "guides" / "controller.md").read_text("utf-8")
    (tmp_path / "depth_p.py").write_text(guide.split("```python\n# depth_p.py\n", 1)[1].split("```", 1)[0])
    mine = tmp_path / "mine"
    _run(
        subenv,
        "evaluate",
        "--plugins",
        "depth_p.py",
        "--controllers",
        "depth_p,thesis",
        "--suite",
        "tiny",
        "--episodes",
        "1",
        "--no-plots",
        "--no-progress",
        "--out",
        mine,
        cwd=tmp_path,
    )
    assert [row["controller"] for row in csv.DictReader((mine / "results.csv").open())] == ["depth_p"] * 2 + [
        "thesis"
    ] * 2

    bare = _run(subenv, cwd=tmp_path, ok=False)
    assert bare.returncode == 2 and "commands:" in bare.stderr
