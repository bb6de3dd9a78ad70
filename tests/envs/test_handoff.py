"""The vector environment's workers (subenv.envs.handoff): polling between steps changes no result."""

from __future__ import annotations

import time

import numpy as np

from subenv.envs import DivePlaneVectorEnv
from subenv.envs import transition as tr
from subenv.envs.handoff import BUDGET, IDLE, SPIN_WHEN_GAP_S, STATE, Crew
from subenv.envs.vector import _thread_pool


def _pair(n: int, scenario: str) -> tuple[DivePlaneVectorEnv, DivePlaneVectorEnv]:
    envs = DivePlaneVectorEnv(num_envs=n, threads=1, scenario=scenario), DivePlaneVectorEnv(
        num_envs=n, threads=2, scenario=scenario)
    for env in envs:
        env.reset(seed=3)
    return envs


def _assert_identical(a, b) -> None:
    for x, y in zip(a[:4], b[:4]):
        np.testing.assert_array_equal(x, y)
    assert a[4].keys() == b[4].keys()
    for key in a[4]:
        np.testing.assert_array_equal(a[4][key], b[4][key], err_msg=key)


def _busy_wait(seconds: float) -> None:
    end = time.perf_counter() + seconds
    while time.perf_counter() < end:
        pass


def test_steps_close_together_keep_the_worker_polling_and_change_nothing():
    serial, threaded = _pair(256, "Randomized")
    actions = np.random.default_rng(0).uniform(-1, 1, size=(60, 256, 1))
    trace = [threaded.step(a) for a in actions]  # (nothing else between the steps)
    worker = threaded._crew.workers[0]
    polling, starts, chunks = worker.polling, worker.starts, worker.chunks
    for a, result in zip(actions, trace):
        _assert_identical(result, serial.step(a))
    assert polling
    assert starts < 30  # most steps found the worker polling (it is started after a pause)
    assert chunks >= 30  # and it stepped rows in most steps


def test_workers_do_not_poll_while_the_caller_works_between_steps():
    """0.3 ms between steps (a policy's forward pass) is beyond SPIN_WHEN_GAP_S: every step posts a
    budget of 0 polls, so no worker polls through the caller's work."""
    assert SPIN_WHEN_GAP_S < 0.3e-3
    serial, threaded = _pair(128, "Nominal")
    actions = np.random.default_rng(4).uniform(-1, 1, size=(30, 128, 1))
    trace, budgets = [], []
    for a in actions:
        trace.append(threaded.step(a))
        budgets.append(int(threaded._crew.workers[0]._mailbox[BUDGET]))
        _busy_wait(0.3e-3)
    assert budgets == [0] * len(actions)
    for a, result in zip(actions, trace):
        _assert_identical(result, serial.step(a))


def test_a_worker_leaves_after_a_pause_and_the_next_step_starts_it_again():
    serial, threaded = _pair(1024, "Nominal")
    rng = np.random.default_rng(1)
    actions = rng.uniform(-1, 1, size=(20, 1024, 1))
    trace = [threaded.step(a) for a in actions]
    worker = threaded._crew.workers[0]
    assert worker.polling
    for a, result in zip(actions, trace):
        _assert_identical(result, serial.step(a))
    starts, future = worker.starts, worker._future
    time.sleep(0.05)  # far beyond the polling budget
    future.result(timeout=5)  # the worker's thread has returned
    assert int(worker._mailbox[STATE]) == IDLE and not worker.polling
    actions = rng.uniform(-1, 1, size=(1024, 1))
    _assert_identical(threaded.step(actions), serial.step(actions))
    assert worker.starts == starts + 1


def test_every_row_is_stepped_once_whoever_claims_it():
    """The caller and a worker claim chunks of each step while the worker's budget runs out as the
    next step comes, and the caller spends a while on its own work in the middle of the step (as it
    does on resets). Budgets and pauses are drawn around each other, so that steps meet polling
    workers, leaving ones, and ones that start after the caller has stepped every row and taken the
    step back. Every step's results equal one thread's. (Claims by a plain store instead of the
    compare-and-swap fail this test.)"""
    n = 256
    reference, env = _pair(n, "Randomized")
    crew, pool = Crew(1, min_rows=16), _thread_pool(2)
    worker = crew.workers[0]
    bound = (env._rows, env._obs, env._rngs, env._cfg, env._hull)
    rng = np.random.default_rng(2)
    active = np.ones(n, dtype=bool)
    posts = 3000
    all_actions = rng.uniform(-1, 1, size=(posts, n, 1))
    budgets = rng.uniform(0, 60e-6, size=posts)
    budgets[::50] = 1.0  # (these the next post finds polling)
    pauses = rng.uniform(0, 40e-6, size=(posts, 2))
    reports = np.empty((posts, tr.N_REPORT, n))
    chunks = []
    for k in range(posts):
        crew.step(pool, bound, all_actions[k], active, reports[k], float(budgets[k]),
                  during=lambda k=k: _busy_wait(pauses[k, 0]))
        chunks.append(worker.chunks)
        _busy_wait(pauses[k, 1])
    future = worker.stop()
    future.result(timeout=5)  # stop() makes a polling worker leave
    for k in range(posts):
        expected = np.empty((tr.N_REPORT, n))
        tr.step_batch(reference._rows, all_actions[k], active, reference._obs, reference._rngs, 0, reference._cfg,
                      reference._hull, expected)
        np.testing.assert_array_equal(reports[k], expected, err_msg=f"post {k}")
    np.testing.assert_array_equal(env._rows, reference._rows)
    np.testing.assert_array_equal(env._obs, reference._obs)
    assert 1 < worker.starts < posts  # both: workers that left, and posts that found one polling
    assert worker.taken_back > 0  # and steps the caller took back
    assert np.count_nonzero(np.diff(chunks) > 0) > posts // 10  # the worker stepped rows in many steps


def test_new_arrays_start_a_new_session():
    reference, env = _pair(64, "Nominal")
    other_reference, other = _pair(64, "LowSpeed")
    crew, pool = Crew(1, min_rows=8), _thread_pool(2)
    worker = crew.workers[0]
    active = np.ones(64, dtype=bool)
    actions = np.full((64, 1), 0.3)
    futures = []
    for ref, target in ((reference, env), (other_reference, other)):
        bound = (target._rows, target._obs, target._rngs, target._cfg, target._hull)
        for _ in range(3):
            expected, report = np.empty((tr.N_REPORT, 64)), np.empty((tr.N_REPORT, 64))
            tr.step_batch(ref._rows, actions, active, ref._obs, ref._rngs, 0, ref._cfg, ref._hull, expected)
            crew.step(pool, bound, actions, active, report, 60.0)  # (a minute's polling)
            np.testing.assert_array_equal(report, expected)
            np.testing.assert_array_equal(target._rows, ref._rows)
        futures.append(worker._future)
    assert worker.starts == 2 and futures[0] is not futures[1]
    futures[0].result(timeout=5)  # the first session's worker left when the arrays changed, not after its budget
    worker.stop().result(timeout=5)  # and stop() sends a polling worker away
