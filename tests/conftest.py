"""Shared fixtures, the opt-in ``slow`` marker, and a summary of measured figures."""

from __future__ import annotations

import contextlib
import io
import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any, NamedTuple

import pytest
from hypothesis import settings

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")  # pygame renders headless in tests
os.environ.setdefault("MPLBACKEND", "Agg")
# One OpenBLAS thread (read when numpy/scipy load, which is after this file). The tests' matrices are
# at most 10 x 10: more threads do not split the work (the results are bitwise the same) but each call
# then waits for the pool; on 2 shared cores one gain-schedule design of the LQR baselines (190 CARE
# solves) took 1.5-3 s instead of 0.12 s.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
# At least two numba threads (read once, when numba is first imported), so that the tests that step a
# vector environment on two threads run on a one-core machine too: results never depend on it.
os.environ["NUMBA_NUM_THREADS"] = str(
    max(2, int(os.environ.get("NUMBA_NUM_THREADS", "0") or 0), os.cpu_count() or 1)
)
# JAX's persistent compilation cache (read when jax is imported): the JAX tests compile the same programs
# in several tests and in both workers (an id's step in tests/jax/test_env.py and test_dynamics.py, the
# sea's twice over); XLA's cache, keyed by the program, the JAX version and the device, compiles each once
# (tests/jax with tests/agents/test_jax_ppo.py from an empty cache: 149 s -> 120 s), and a later run on
# the machine loads them. The results are the same programs' either way. At most 256 MB, the least
# recently used dropped (a run of the suite writes about 10 MB; each edit of the kernels, as much again).
os.environ.setdefault(
    "JAX_COMPILATION_CACHE_DIR", str(Path(__file__).resolve().parents[1] / ".pytest_cache" / "jax")
)
os.environ.setdefault("JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS", "0.5")
os.environ.setdefault("JAX_COMPILATION_CACHE_MAX_SIZE", str(256 * 2**20))

# The property tests draw the same examples on every run and machine (from a seed made of each test's source,
# so an edit of a test may draw others: keep a failure it found as an @example), keep no database of earlier
# failures between runs, and set no time limit per example, which a busy machine would break. Explore with
# fresh random examples by pytest --hypothesis-profile=default (Hypothesis' own settings).
settings.register_profile("ci", derandomize=True, database=None, deadline=None)
settings.load_profile("ci")

_MEASURED: list[tuple[str, str]] = []


@pytest.fixture(scope="session", autouse=True)
def _sb3_logs_in_the_sessions_folder(tmp_path_factory: pytest.TempPathFactory) -> None:
    """Stable-Baselines3 makes a folder for every ``learn()`` of a model without a logger set, even one that
    logs nothing (``tempfile``'s ``SB3-<time>``, which nothing removes: 162 in /tmp after a day's runs);
    the tests' and their subprocesses' go to the session's temporary folder (SB3's ``SB3_LOGDIR``)."""
    os.environ["SB3_LOGDIR"] = str(tmp_path_factory.mktemp("sb3"))


@pytest.fixture
def compiled_signatures() -> Callable[[], dict[str, int]]:
    """A function that counts the signatures each of the transition's kernels has compiled (or loaded) in
    this process: what a test compares before and after to show that a step compiled nothing new."""
    from numba.core.registry import CPUDispatcher

    from subenv.envs import transition

    def count() -> dict[str, int]:
        return {
            name: len(f.signatures) for name, f in vars(transition).items() if isinstance(f, CPUDispatcher)
        }

    return count


def pytest_configure(config: pytest.Config) -> None:
    """Register the controllers as this checkout's ``pyproject.toml`` declares them.

    The installed metadata, from which :func:`subenv.evaluation.controller_names` would read them,
    may be another checkout's or older than the declarations (an editable install keeps the entry
    points it was installed with; ./dev reinstalls when pyproject.toml changes). The installed path
    itself is tested from a wheel in ``tests/test_packaging.py``.
    """
    if not (config.rootpath / "subenv").is_dir():
        return  # (a project that tests/test_conftest.py makes: no controllers, and no import of subenv)
    from importlib.metadata import EntryPoint

    from subenv.evaluation import ENTRY_POINT_GROUP, discover_controllers

    try:
        import tomllib
    except ModuleNotFoundError:  # Python 3.10
        import tomli as tomllib  # type: ignore[no-redef]

    pyproject = tomllib.loads((Path(__file__).resolve().parents[1] / "pyproject.toml").read_text())
    declared = pyproject["project"]["entry-points"][ENTRY_POINT_GROUP]
    discover_controllers(EntryPoint(name, value, ENTRY_POINT_GROUP) for name, value in declared.items())


# Until the compiled kernels are in numba's on-disk cache (a fresh checkout, an edit of their sources), the
# first call of each in a process compiles it, 10-20 s on a quiet core for the environments' step. Each
# pytest-xdist worker would compile those its first tests call, both workers the same ones at once, and so
# would a test's subprocess that starts before they are cached. So a run with workers compiles them first,
# once, before the workers start, in two processes for two cores (cold, here: the steps 25 s; the model's
# functions 8 s, then the two kernels below, 13 s); every process then loads them. A copied environment's
# step is the same compiled step (its arrays as read-only as the original's). (tests/dynamics/test_model.py
# and tests/test_packaging.py compile in caches of their own, on purpose.)
_WARM_UP = (
    # The environments' step as gym.make builds them, and the vector environment's on two threads.
    """
import numpy as np, gymnasium as gym, subenv
env = gym.make("subenv/DivePlane-v0"); env.reset(seed=0); env.step(np.zeros(1, dtype=np.float32))
vec = gym.make_vec("subenv/Nominal-v0", num_envs=4, threads=2); vec.reset(seed=0); vec.step(np.zeros((4, 1)))
""",
    # The batched right-hand side and hull integrals, for one state and for rows of them; then the kernels
    # that no environment calls, which the other program leaves this one the time for: the public block
    # integrator, and the MPC's condensing where its extra is installed (7 s and 6 s cold).
    """
import numpy as np, subenv
from subenv.dynamics import CONTROL_PERIOD_S, control_period, crossflow_integrals, derivatives, model_params
from subenv.dynamics.free_surface import suction
from subenv.envs.dive_plane import OBSERVATION_NAMES
from subenv.evaluation import controller_names, make_controller
vehicle, x = subenv.load_vehicle("suboff"), np.linspace(-1.0, 1.0, 7)
params = model_params(vehicle)
derivatives(np.zeros(4), 1.0, 0.0, 0.0, params)
derivatives(np.stack([0.1 * x, 0.05 * x, 0.01 * x, 10 + x], axis=-1), 1.2, 0.05 * x, -0.02, params)
crossflow_integrals(params.hull, 0.05 * x, 0.01 * x)
suction(params.hull, 0.1 * x, 1.0 + 0.2 * x, 1.0, 1000.0)
control_period(np.zeros((2, 4)), 0.0, CONTROL_PERIOD_S, 1.0, 0.0, 0.0, 0.0, params)
if "mpc" in controller_names():  # (registered where its extra is installed)
    mpc, obs = make_controller("mpc"), np.zeros((1, len(OBSERVATION_NAMES)), dtype=np.float32)
    obs[0, OBSERVATION_NAMES.index("speed_mps")] = 1.0
    mpc.reset_batch([{}], vehicle)
    mpc.act_batch(obs)
""",
)


def pytest_sessionstart(session: pytest.Session) -> None:
    # (before pytest-xdist's own, which starts the workers: it is trylast)
    config = session.config
    # (Only where there are kernels to compile: not in the projects that tests/test_conftest.py makes.)
    checkout = (config.rootpath / "subenv" / "dynamics").is_dir()
    if checkout and config.getoption("numprocesses", None) and not config.option.collectonly:
        # (Their stderr is the session's: where they compile, subenv says so there, once each.)
        processes = [subprocess.Popen([sys.executable, "-c", program]) for program in _WARM_UP]
        for process in processes:  # (one that fails leaves the compiling to the tests, which report why)
            process.wait()


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption("--run-slow", action="store_true", help="also run tests marked slow (minutes)")


# Under pytest-xdist, ./dev test runs ``-n auto --dist loadgroup --no-loadscope-reorder``: tests marked
# ``xdist_group(name)`` run in one worker, the group's. Each test file is one group, so that a module-scoped
# fixture (the shipped cards' 300 episodes, the training runs per algorithm, the rl_zoo3 trainings) is
# computed once; and the files whose tests use one of these session fixtures are one group, named after
# it, so that it is computed once too. One Ray instance in the suite also means that the sweep test which
# kills "a Ray worker running a chunk" finds its own.
SHARED_SESSION_FIXTURES = ("analysis_report", "local_ray", "small_run")
# The groups that take most of the suite's time (from an empty cache, on 2 cores: 45-95 s each), longest
# first, are collected first, and ./dev test keeps that order (--no-loadscope-reorder: pytest-xdist would
# order the groups by their number of tests). Started last, the wheel's test (one test, 50 s) left one
# worker idle for the last 36 s of a 330 s run; this way the two workers end together.
LONGEST_FIRST = (
    "tests/jax/test_env.py",
    "tests/test_docs.py",
    "local_ray",
    "tests/test_packaging.py",
    "tests/agents/test_jax_ppo.py",
    "tests/jax/test_dynamics.py",
)


@pytest.hookimpl(tryfirst=True)  # before pytest-xdist reads the marks, in its own hook of this name
def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    shared: dict[str, set[str]] = {}
    for item in items:
        file = item.nodeid.split("::", 1)[0]
        # (tests/envs/test_rllib.py's local_ray is a module fixture of its own: RLlib's, run in .venv-gym12/)
        if file != "tests/envs/test_rllib.py":
            shared.setdefault(file, set()).update(set(item.fixturenames) & set(SHARED_SESSION_FIXTURES))
    groups: dict[str, str] = {}
    for item in items:
        file = item.nodeid.split("::", 1)[0]
        names = shared.get(file, set())
        if len(names) > 1:
            raise pytest.UsageError(
                f"{file} uses the session fixtures {sorted(names)}, each computed in its own group of files "
                "(tests/conftest.py): move the tests that use one of them to another file"
            )
        groups[item.nodeid] = group = min(names) if names else file
        item.add_marker(pytest.mark.xdist_group(group))
    rank = {group: k for k, group in enumerate(LONGEST_FIRST)}
    items.sort(key=lambda item: rank.get(groups[item.nodeid], len(rank)))  # (stable: the rest as collected)
    if config.getoption("--run-slow"):
        return
    skip = pytest.mark.skip(reason="slow: opt in with --run-slow")
    for item in items:
        if "slow" in item.keywords:
            item.add_marker(skip)


@pytest.hookimpl(optionalhook=True)  # (a hook of pytest-xdist, which may not be installed)
def pytest_xdist_node_collection_finished(node, ids: list[str]) -> None:  # type: ignore[no-untyped-def]
    # pytest-xdist's workers tell its loadgroup scheduler a test's group by appending "@<group>" to the test's
    # id, which pytest 9.2 no longer lets them change (pytest-xdist#1386, open): nothing is grouped then, and
    # without a word, each worker computing the shared fixtures again. Hence the test extra's pytest<9.2.
    if node.config.getoption("dist") == "loadgroup":
        ungrouped = [nodeid for nodeid in ids if "@" not in nodeid]
        if ungrouped:
            raise pytest.UsageError(
                f"pytest-xdist's --dist loadgroup did not group {ungrouped[0]} (pytest-xdist#1386, on "
                f"pytest {pytest.__version__}): install the test extra, which requires pytest<9.2"
            )


@pytest.fixture
def report(request: pytest.FixtureRequest):  # type: ignore[no-untyped-def]
    """Record a measured figure; all of them are printed in the terminal summary.

    They travel as the test's ``user_properties``, which pytest-xdist sends from its workers."""

    def _report(name: str, value: str) -> None:
        request.node.user_properties.append(("measured", (name, value)))

    return _report


def pytest_runtest_logreport(report: pytest.TestReport) -> None:
    if report.when == "call":
        _MEASURED.extend(tuple(value) for key, value in report.user_properties if key == "measured")


def pytest_terminal_summary(terminalreporter, exitstatus, config) -> None:  # type: ignore[no-untyped-def]
    if _MEASURED:
        terminalreporter.section("measured")
        for name, value in _MEASURED:
            terminalreporter.write_line(f"{name}: {value}")


@pytest.fixture(scope="session")
def suboff():
    from subenv import load_vehicle

    return load_vehicle("suboff")


class AnalysisReport(NamedTuple):
    folder: Path
    """Where ``subenv analyze --out <folder>`` wrote the report; it did not exist before."""
    exit_code: int
    printed: str
    """What the command printed (stdout)."""
    hopf: Any
    """``hopf_findings(load_vehicle("suboff"))`` (a ``HopfFindings``), which the report computed."""


@pytest.fixture(scope="session")
def analysis_report(tmp_path_factory: pytest.TempPathFactory) -> AnalysisReport:
    """The reproduction report of Riedel (1993), written once per session (tens of seconds).

    ``subenv analyze --out <folder>`` writes it: the command calls ``write_findings(folder,
    load_vehicle("suboff"))``, so the tests of ``write_findings`` (tests/analysis) and of the command
    (tests/test_cli.py) share this one folder. Its parent holds nothing else. Tests read it and must
    not change it; one that needs an existing report to replace works on a copy.

    The Hopf findings the report computes (``hopf_findings(vehicle)``, half of its time) are kept as they
    were returned, for tests/analysis/test_hopf.py, which would otherwise compute them again.
    """
    import subenv.analysis.report
    from subenv import load_vehicle
    from subenv.cli import main

    computed = []
    real = subenv.analysis.report.hopf_findings

    def recorded(vehicle):  # type: ignore[no-untyped-def]
        found = real(vehicle)
        computed.append((vehicle, found))
        return found

    folder = tmp_path_factory.mktemp("analysis") / "report"
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed), pytest.MonkeyPatch.context() as patch:
        patch.setattr(subenv.analysis.report, "hopf_findings", recorded)
        exit_code = main(["analyze", "--out", str(folder)])
    ((vehicle, hopf),) = computed
    assert vehicle == load_vehicle("suboff")
    return AnalysisReport(folder, exit_code, printed.getvalue(), hopf)


@pytest.fixture(scope="session")
def local_ray():  # type: ignore[no-untyped-def]
    """One local Ray instance with 2 CPUs for every test that runs Ray tasks or Tune trials (a start costs
    5-10 s); the functions under test use it instead of starting their own."""
    ray = pytest.importorskip("ray", reason="the 'ray' extra is not installed")
    # Ray's raylet starts its workers at nice 15 (RAY_worker_niceness): beside other CPU-bound work, as on a
    # busy CI machine, a Tune trial then got about 1% of a core and the suite did not end. At 0 they share
    # the cores as the test process does (as Ray's own job manager sets it for a job's workers).
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("RAY_worker_niceness", "0")
        ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False, configure_logging=False)
    yield
    ray.shutdown()
