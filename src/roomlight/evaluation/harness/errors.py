"""Errors of the synthetic benchmark (all :class:`~roomlight.errors.RoomlightError`)."""

from __future__ import annotations

from roomlight.errors import RoomlightError

__all__ = ["BenchError"]


class BenchError(RoomlightError):
    """A benchmark input, directory or result is missing or not what the benchmark expects."""
