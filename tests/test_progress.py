"""Progress bars in logs: whole lines, at most one per interval, instead of an update per step."""

from __future__ import annotations

import io
import time

from roomlight.core.progress import progress_bar


class _Terminal(io.StringIO):
    def isatty(self):
        return True


def test_a_log_gets_a_line_per_interval_not_per_step():
    log = io.StringIO()
    steps, pause, every = 120, 0.01, 0.4
    t0 = time.perf_counter()
    with progress_bar(total=steps, desc="fit", stream=log, interval=every) as bar:
        for _ in range(steps):
            time.sleep(pause)
            bar.update()
    elapsed = time.perf_counter() - t0
    text = log.getvalue()
    assert "\r" not in text and "\x1b" not in text
    lines = text.splitlines()
    assert all(line.startswith("fit:") for line in lines)
    # the first line, one per full interval, and the last one when the bar closes
    assert 2 <= len(lines) <= elapsed / every + 2, lines
    assert lines[-1].startswith("fit: 100%") and f"{steps}/{steps}" in lines[-1]


def test_a_terminal_gets_the_usual_in_place_bar():
    term = _Terminal()
    with progress_bar(total=50, desc="fit", stream=term, mininterval=0) as bar:
        for _ in range(50):
            bar.update()
    assert term.getvalue().count("\r") > 10


def test_disabled_bars_print_nothing():
    log = io.StringIO()
    for _ in progress_bar(range(10), stream=log, disable=True):
        pass
    assert log.getvalue() == ""
