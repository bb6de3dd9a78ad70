"""Progress on a terminal and in a log file, and the notice that the first run compiles the physics."""

from __future__ import annotations

import io
import re

import gymnasium as gym
import pytest

from subenv.envs import _compiling as compiling
from subenv.evaluation.progress import LOG_LINES, Progress


class Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


LINE = re.compile(
    r"^evaluate: (\d+)/(\d+) episodes, (\d+)% \(lqr on LowSpeed\); (\d+:\d\d) elapsed, ETA (\d+:\d\d|\?)$"
)


@pytest.mark.parametrize("total", [8, 40, 3600])
def test_without_a_terminal_a_line_every_five_percent(total: int) -> None:
    log = io.StringIO()
    bar = Progress(total, stream=log)
    bar.describe("lqr on LowSpeed")
    for _ in range(total // 4):
        bar.update(4)  # (the batched harness reports its episodes in bursts)
    bar.close()
    lines = log.getvalue().splitlines()
    assert len(lines) == min(LOG_LINES, total // 4)
    done = [int(LINE.match(line).group(1)) for line in lines]  # type: ignore[union-attr]
    assert done == sorted(set(done)) and done[-1] == total
    assert lines[-1].startswith(f"evaluate: {total}/{total} episodes, 100% ")
    assert all(
        b - a <= max(4, total // LOG_LINES + 4) for a, b in zip([0, *done], done, strict=False)
    )  # no long silence


def test_a_line_says_done_elapsed_and_time_left() -> None:
    bar = Progress(40, stream=io.StringIO())
    bar.done = 10
    assert bar.line(30.0) == "evaluate: 10/40 episodes, 25%; 0:30 elapsed, ETA 1:30"
    bar.done = 0
    assert bar.line(0.0).endswith("ETA ?")
    bar.done = 30
    assert bar.line(3 * 3600.0).endswith("3:00:00 elapsed, ETA 1:00:00")


def test_on_a_terminal_the_bar_and_no_log_lines() -> None:
    terminal = Terminal()
    bar = Progress(8, stream=terminal)
    bar.update(8)
    bar.close()
    shown = terminal.getvalue()
    assert "8/8" in shown and "\r" in shown and "ETA" not in shown


def test_disabled_prints_nothing() -> None:
    for stream in (io.StringIO(), Terminal()):
        bar = Progress(8, enabled=False, stream=stream)
        bar.update(8)
        bar.close()
        assert stream.getvalue() == ""


@pytest.mark.parametrize("vector", [False, True])
def test_a_plain_env_says_it_compiles_on_its_first_reset_and_step_only(vector, monkeypatch) -> None:
    """gym.make / make_vec users see the notice too: each env's first reset and first step run under
    it (a slow kernel call stands in for a compilation), the later calls go straight to the kernels."""
    entered: list[str] = []

    class Recording:
        def __enter__(self) -> None:
            entered.append("enter")

        def __exit__(self, *exc: object) -> None:
            entered.append("exit")

    monkeypatch.setattr(compiling, "compile_notice", Recording)
    env = (
        gym.make_vec("subenv/LowSpeed-v0", num_envs=2, vectorization_mode="vector_entry_point")
        if vector
        else gym.make("subenv/LowSpeed-v0")
    )
    env.reset(seed=0)
    for _ in range(3):
        env.step(env.action_space.sample())
    env.reset(seed=1)
    assert entered == ["enter", "exit"] * 2  # the first reset, the first step
