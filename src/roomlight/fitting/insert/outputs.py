"""The files of ``roomlight insert``: the composite (PNG and EXR), the new objects' mask, the shadow
ratio and ``insert.json``."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from roomlight.fitting.insert.composite import InsertResult

__all__ = ["write_insert_outputs", "INSERT_FORMAT"]

INSERT_FORMAT = "roomlight.insert"


def _srgb8(linear: np.ndarray) -> np.ndarray:
    from roomlight.core.color import linear_to_srgb

    return np.rint(linear_to_srgb(np.clip(linear, 0.0, 1.0)) * 255).astype(np.uint8)


def write_insert_outputs(result: InsertResult, out_png) -> dict[str, Path]:
    """Write the composite at ``out_png`` (sRGB PNG) and, beside it, ``<stem>.exr`` (linear, the same
    pixels unclipped), ``object_mask.png`` (coverage of the new objects, 0-255), ``shadow.png`` (the
    with / without luminance ratio, 128 = unchanged, 0 = black, 255 = twice as bright) and
    ``insert.json``; returns the paths by role."""
    from roomlight.core.io import save_png, write_exr
    from roomlight.fitting.photo.outputs import atomic_write

    png = Path(out_png)
    folder = png.parent
    folder.mkdir(parents=True, exist_ok=True)
    paths = {"composite_png": png, "composite_exr": png.with_suffix(".exr"),
             "object_mask": folder / "object_mask.png", "shadow": folder / "shadow.png",
             "json": folder / "insert.json"}
    atomic_write(paths["composite_png"], lambda p: save_png(p, _srgb8(result.composite)))
    atomic_write(paths["composite_exr"],
                 lambda p: write_exr(p, {c: result.composite[..., i] for i, c in enumerate("RGB")}))
    atomic_write(paths["object_mask"], lambda p: save_png(p, np.rint(result.coverage * 255).astype(np.uint8)))
    shade = np.rint(np.clip(result.shadow, 0.0, 2.0) * 127.5).astype(np.uint8)
    atomic_write(paths["shadow"], lambda p: save_png(p, shade))
    info = {"format": INSERT_FORMAT, "version": 1, **result.info,
            "files": {k: v.name for k, v in paths.items()}}
    atomic_write(paths["json"], lambda p: p.write_text(json.dumps(info, indent=2)))
    return paths
