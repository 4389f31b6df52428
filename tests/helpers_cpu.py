"""A busy process for the tests of the thread policy and of repeatability beside other jobs."""

from __future__ import annotations

import time


def spin_for(seconds: float) -> None:
    """Keep one CPU busy for ``seconds`` (a pure-Python loop, like any other job); run it in a child process."""
    end = time.perf_counter() + seconds
    while time.perf_counter() < end:
        pass
