"""The notice that the first run compiles the physics: it goes by numba's compilations, not by time."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numba
import numba.core.event
import numba.typed
import numpy as np

from subenv.envs import _compiling as compiling
from subenv.envs._compiling import COMPILE_NOTICE


@numba.njit
def _compiled(x: float) -> float:
    return x + 1.0


def test_a_slow_first_call_that_compiles_nothing_says_nothing(capsys) -> None:
    """A loaded machine: the first reset loads everything from numba's cache but takes seconds."""
    _compiled(1.0)  # its signature is compiled before the first call
    notice = compiling._CompileNotice()
    with notice:
        _compiled(2.0)
        time.sleep(3.0)  # longer than the 2 s after which the notice used to be printed
    assert not notice.said
    assert capsys.readouterr().err == ""


def test_a_first_call_that_compiles_says_so_once(capsys) -> None:
    notice = compiling._CompileNotice()
    for _ in range(2):  # two first calls that each compile a new function: one notice in all
        with notice:
            numba.njit(lambda x: x * 2.0)(1.0)
    with notice:
        _compiled(3.0)
    assert notice.said
    assert capsys.readouterr().err == COMPILE_NOTICE + "\n"


def test_compilations_outside_a_first_call_say_nothing(capsys) -> None:
    notice = compiling._CompileNotice()
    with notice:
        pass
    numba.njit(lambda x: x - 1.0)(1.0)
    assert not notice.said
    assert capsys.readouterr().err == ""


def test_numbas_own_functions_say_nothing(capsys) -> None:
    """An environment's reset builds a numba typed list of generators, whose functions numba compiles in
    every process (its cache does not keep them): that is not the physics compiling."""

    class Count(numba.core.event.Listener):
        compiled = 0

        def on_start(self, compilation: numba.core.event.Event) -> None:
            self.compiled += 1

        def on_end(self, compilation: numba.core.event.Event) -> None:
            pass

    notice, count = compiling._CompileNotice(), Count()
    with notice, numba.core.event.install_listener("numba:compile", count):
        numba.typed.List([np.int16(3)])  # (a type no other test puts in a typed list: it compiles)
    assert count.compiled > 0 and not notice.said
    assert capsys.readouterr().err == ""


_RESET_AND_STEP = """
import numpy as np, gymnasium as gym, subenv

env = gym.make("subenv/DivePlane-v0")
env.reset(seed=0)
print(env.step(np.zeros(1, dtype=np.float32))[0].shape)
"""


def test_a_run_of_an_environment_with_its_kernels_cached_says_nothing() -> None:
    """Two runs of an environment: the second loads every kernel from numba's cache (the first may
    compile them: a fresh checkout) and says nothing (it said "compiling the dynamics" on every run)."""
    runs = [
        subprocess.run([sys.executable, "-c", _RESET_AND_STEP], capture_output=True, text=True, timeout=600)
        for _ in range(2)
    ]
    assert [run.stdout for run in runs] == ["(8,)\n"] * 2, [run.stderr[-2000:] for run in runs]
    assert COMPILE_NOTICE not in runs[1].stderr


_CACHED_KERNEL = """
import numba


@numba.njit(cache=True)
def kernel(x):
    return x * x + 1.0
"""

_FIRST_CALL = """
from kernel import kernel
from subenv.envs._compiling import compile_notice

with compile_notice():
    print(kernel(3.0))
"""


def test_a_cold_cache_says_so_and_a_warm_one_does_not(tmp_path: Path) -> None:
    """Two processes, as two runs of ``subenv evaluate``: the first compiles into an empty
    ``NUMBA_CACHE_DIR`` and prints the notice, the second loads from it and prints nothing."""
    (tmp_path / "kernel.py").write_text(textwrap.dedent(_CACHED_KERNEL))
    env = {
        **os.environ,
        "NUMBA_CACHE_DIR": str(tmp_path / "cache"),
        "PYTHONPATH": os.pathsep.join(filter(None, [str(tmp_path), os.environ.get("PYTHONPATH")])),
    }

    def run() -> subprocess.CompletedProcess[str]:
        return subprocess.run(
            [sys.executable, "-c", _FIRST_CALL], env=env, capture_output=True, text=True, timeout=600
        )

    cold, warm = run(), run()
    assert (cold.returncode, warm.returncode) == (0, 0), (cold.stderr[-2000:], warm.stderr[-2000:])
    assert cold.stdout == warm.stdout == "10.0\n"
    assert COMPILE_NOTICE in cold.stderr
    assert COMPILE_NOTICE not in warm.stderr
    assert any((tmp_path / "cache").rglob("*.nbi"))  # the second run had an index to load from
