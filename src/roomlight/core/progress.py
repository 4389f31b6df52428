"""Progress bars that suit both a terminal and a log file.

On a terminal, ``progress_bar`` is a plain tqdm bar. When the stream is not a terminal (a log
file, ``make demo > log``, a batch job), the bar prints one whole line at most every
``LOG_INTERVAL`` seconds (and a last one when it closes) instead of a carriage-return update per
step, with no terminal escape codes. Every progress bar in roomlight goes through here.
"""

from __future__ import annotations

import re
import sys

__all__ = ["LOG_INTERVAL", "progress_bar", "is_terminal"]

#: Seconds between two progress lines when the output is not a terminal.
LOG_INTERVAL = 5.0
_ESCAPES = re.compile(r"\x1b\[[0-9;]*[A-Za-z]")


def is_terminal(stream) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):  # no isatty, or a closed stream
        return False


class _Lines:
    """A file-like wrapper that turns tqdm's in-place updates into one line each."""

    def __init__(self, stream):
        self.stream = stream

    def write(self, s: str) -> int:
        text = _ESCAPES.sub("", s).replace("\r", "").strip()
        if text:
            self.stream.write(text + "\n")
        return len(s)

    def flush(self) -> None:
        self.stream.flush()


def progress_bar(iterable=None, *, total=None, desc: str | None = None, unit: str = "it", disable: bool = False,
                 stream=None, interval: float | None = None, **kwargs):
    """A tqdm bar on ``stream`` (default stderr); see the module docstring for non-terminals.

    ``interval`` overrides ``LOG_INTERVAL``; other keyword arguments go to tqdm.
    """
    from tqdm import tqdm

    stream = sys.stderr if stream is None else stream
    if is_terminal(stream):
        kwargs.setdefault("dynamic_ncols", True)
        kwargs["file"] = stream
    else:
        every = LOG_INTERVAL if interval is None else interval
        kwargs.pop("dynamic_ncols", None)
        kwargs.update(file=_Lines(stream), mininterval=every, maxinterval=max(every, 10.0), ascii=True, ncols=100)
    return tqdm(iterable, total=total, desc=desc, unit=unit, disable=disable, **kwargs)
