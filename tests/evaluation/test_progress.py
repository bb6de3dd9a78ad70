"""Progress on a terminal and in a log file, and the notice that the first run compiles the physics."""

from __future__ import annotations

import io
import re
import time

import pytest

from subenv.evaluation import progress
from subenv.evaluation.progress import COMPILE_NOTICE, LOG_LINES, Progress


class Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


LINE = re.compile(r"^evaluate: (\d+)/(\d+) episodes, (\d+)% \(lqr on LowSpeed\); (\d+:\d\d) elapsed, ETA (\d+:\d\d|\?)$")


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
    assert all(b - a <= max(4, total // LOG_LINES + 4) for a, b in zip([0, *done], done))  # no long silence


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


def test_the_compile_notice_shows_once_while_the_first_calls_are_slow(monkeypatch, capsys) -> None:
    monkeypatch.setattr(progress, "NOTICE_DELAY_S", 0.0)
    notice = progress._CompileNotice()
    with notice:  # a first call that lasts until the notice is out, as a compilation outlasts the delay
        deadline = time.monotonic() + 30.0
        while notice.pending and time.monotonic() < deadline:
            time.sleep(0.01)
    with notice:  # said once: no timer now
        assert notice._timer is None
    assert capsys.readouterr().err == COMPILE_NOTICE + "\n"

    settled = progress._CompileNotice()
    settled.settled()  # the kernels are loaded: the blocks arm nothing
    with settled:
        assert settled._timer is None
