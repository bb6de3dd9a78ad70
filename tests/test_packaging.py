"""A wheel built from the repository installs into a clean venv and its environments make."""

from __future__ import annotations

import subprocess
import sys
import venv
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_wheel_installs_into_a_clean_venv(tmp_path: Path):
    dist = tmp_path / "dist"
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q",
                    "-w", str(dist), str(ROOT)], check=True)
    (wheel,) = dist.glob("subenv-*.whl")
    names = zipfile.ZipFile(wheel).namelist()
    assert "subenv/vehicles/data/suboff.toml" in names and "subenv/py.typed" in names
    assert not any(n.startswith(("baselines/", "agents/", "tests/")) for n in names)

    env_dir = tmp_path / "venv"
    venv.EnvBuilder(with_pip=True).create(env_dir)
    python = env_dir / "bin" / "python"
    subprocess.run([str(python), "-m", "pip", "install", "-q", "--no-compile", str(wheel)], check=True)
    code = (
        "import gymnasium as gym, subenv, pathlib\n"
        "assert 'site-packages' in pathlib.Path(subenv.__file__).as_posix()\n"
        "env = gym.make('subenv/DivePlane-v0')\n"
        "obs, info = env.reset(seed=0)\n"
        "obs, r, te, tr, info = env.step(env.action_space.sample())\n"
        "print(obs.shape, round(info['critical_speed_mps'], 3) > 0)\n"
    )
    out = subprocess.run([str(python), "-c", code], capture_output=True, text=True, check=True, cwd=tmp_path)
    assert out.stdout.strip() == "(8,) True"
