"""JSON for what roomlight writes: numpy scalars and arrays, and paths, as plain JSON values."""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["json_default"]


def json_default(obj):
    """``json.dumps``'s ``default``: numpy scalars as numbers, arrays as lists, paths as strings."""
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, Path):
        return str(obj)
    raise TypeError(f"not JSON serialisable: {type(obj).__name__}")
