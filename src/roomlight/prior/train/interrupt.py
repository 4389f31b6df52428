"""Ctrl-C and SIGTERM during training: finish the current step, then stop.

An interrupt that lands in the middle of an optimiser step would leave the step counter, the
data position and the random generators out of step with one another, and a checkpoint written
then resumes one batch late. :func:`deferred_interrupts` installs handlers that only record the
signal; the loop asks :attr:`InterruptFlag.signum` at the end of each step and stops there, so
the checkpoint it writes is the state an uninterrupted run has after the same step. A second
signal while the first is pending stops at once, without a checkpoint.
"""

from __future__ import annotations

import signal
import threading
from contextlib import contextmanager

__all__ = ["checkpoint_interrupted", "Interrupted", "InterruptFlag", "deferred_interrupts"]

SIGNALS = (signal.SIGINT, signal.SIGTERM)


class Interrupted(KeyboardInterrupt):
    """Training stopped by a signal; ``signum`` is SIGINT or SIGTERM (exit status 128 + signum)."""

    def __init__(self, signum: int, clean: bool = True):
        super().__init__(signal.Signals(signum).name)
        self.signum = signum
        #: True when the stop came at the end of a step (a checkpoint of it is consistent).
        self.clean = clean


class InterruptFlag:
    """The first SIGINT / SIGTERM received while installed (None until then)."""

    def __init__(self, note=None):
        self.signum: int | None = None
        self.note = note

    def _handle(self, signum, frame) -> None:
        if self.signum is not None:
            raise Interrupted(signum, clean=False)
        self.signum = signum
        if self.note is not None:
            self.note(f"{signal.Signals(signum).name}: stopping after the current step (again to stop at once)")


@contextmanager
def deferred_interrupts(note=None):
    """Within the block, SIGINT and SIGTERM set the yielded :class:`InterruptFlag` instead of
    raising; outside the main thread (where handlers cannot be installed) the flag stays unset."""
    flag = InterruptFlag(note)
    if threading.current_thread() is not threading.main_thread():
        yield flag
        return
    previous = {s: signal.signal(s, flag._handle) for s in SIGNALS}
    try:
        yield flag
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)


def checkpoint_interrupted(exc: KeyboardInterrupt, save, note, step: int, last_checkpoint) -> None:
    """What a training loop does when ``exc`` stops it: after a clean stop at a step boundary, write a
    checkpoint with ``save()`` and say how to continue; after a second signal mid-step, only name the
    last checkpoint. The caller re-raises ``exc``."""
    if isinstance(exc, Interrupted) and not exc.clean:
        note(f"stopped during step {step + 1}; the last checkpoint is {last_checkpoint}")
        return
    path = save()
    note(f"interrupted at step {step}; saved {path}. Run the same command again to continue.")

