"""Errors raised by roomlight.

Every error a user can cause derives from :class:`RoomlightError`; the CLI turns these into a
one-line message and a non-zero exit code instead of a stack trace. Messages name the input,
what was expected, what was received, and (where one exists) how to fix it.
"""

from __future__ import annotations


class RoomlightError(Exception):
    """Base class for errors caused by inputs, configuration or environment."""


class InputFileError(RoomlightError):
    """A file could not be read, or its content is not what the format promises."""

    def __init__(self, path, problem: str, fix: str | None = None):
        self.path = str(path)
        self.problem = problem
        self.fix = fix
        msg = f"{self.path}: {problem}"
        if fix:
            msg += f" ({fix})"
        super().__init__(msg)


class ShapeError(RoomlightError):
    """A tensor or image has the wrong shape (e.g. width != 2 * height)."""


class BackendError(RoomlightError):
    """Mitsuba / Dr.Jit could not start the requested backend."""
