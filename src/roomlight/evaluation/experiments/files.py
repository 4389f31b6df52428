"""Writing an experiment's files so that a kill never leaves half of one: temporary name, then rename."""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import numpy as np

__all__ = ["atomic_json", "atomic_npz", "atomic_text", "finite_json"]


def finite_json(obj):
    """``obj`` with NaN and infinities replaced by None, recursively (strict JSON has no such numbers)."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: finite_json(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [finite_json(v) for v in obj]
    return obj


def atomic_text(path, text: str) -> None:
    path = Path(path)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    tmp.write_text(text)
    os.replace(tmp, path)


def atomic_json(path, data) -> None:
    """``data`` as indented strict JSON (NaN/inf written as null)."""
    atomic_text(path, json.dumps(finite_json(data), indent=2) + "\n")


def atomic_npz(path, **arrays) -> None:
    """Compressed ``.npz`` of ``arrays``."""
    path = Path(path)
    tmp = path.with_name(f".{path.stem}.{os.getpid()}.tmp.npz")
    np.savez_compressed(tmp, **arrays)
    os.replace(tmp, path)
