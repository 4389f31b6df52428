"""Depth map files: radial distance from the capture point, in metres.

Accepted inputs (chosen by extension):

- ``.exr``: the channel ``Z``; otherwise a layered ``*.Z`` channel (e.g. ``depth.Z``), ``Y``,
  ``R``, or the only channel of a single-channel file. Values are metres.
- ``.npy``: an (H, W) or (H, W, 1) array of any real dtype, metres (loaded without pickle).
- ``.png``: a 16-bit grayscale PNG holding **millimetres** (1 mm steps, at most 65.535 m);
  converted to metres. 0 conventionally means "no measurement" and is reported as invalid
  depth by the panorama validation, not here.

Every reader returns (H, W) float32 metres and does not judge the values; checks for
positivity/finiteness live in :mod:`roomlight.core.io.validate`.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from roomlight.errors import InputFileError
from roomlight.core.io.exr import DEPTH_CHANNEL, read_exr, write_exr
from roomlight.core.io.validate import as_numpy_map, check_extension, check_file

__all__ = ["DEPTH_EXTENSIONS", "read_depth", "write_depth", "write_depth_png", "pick_depth_channel"]

DEPTH_EXTENSIONS = (".exr", ".npy", ".png")
#: Largest depth a 16-bit millimetre PNG can hold, in metres.
PNG_MAX_DEPTH_M = 65.535


def pick_depth_channel(channels: dict[str, np.ndarray]) -> str | None:
    """Name of the depth channel in an EXR channel dict, or None if there is no clear one.

    Preference: ``Z``, then a single layered ``<layer>.Z``, ``Y``, ``R``, then the only
    channel of a single-channel file.
    """
    if DEPTH_CHANNEL in channels:
        return DEPTH_CHANNEL
    layered = [n for n in channels if n.endswith(".Z")]
    if len(layered) == 1:
        return layered[0]
    for name in ("Y", "R"):
        if name in channels:
            return name
    if len(channels) == 1:
        return next(iter(channels))
    return None


def read_depth(path: str | os.PathLike) -> np.ndarray:
    """Read a depth map file as (H, W) float32 metres (see the module docstring)."""
    p = check_file(path)
    ext = check_extension(p, DEPTH_EXTENSIONS, "depth map")
    if ext == ".exr":
        channels = read_exr(p)
        name = pick_depth_channel(channels)
        if name is None:
            raise InputFileError(
                p,
                f"no depth channel among {sorted(channels)}; expected 'Z' (or 'Y', 'R', or a "
                "single channel)",
                "rename the depth channel to 'Z'",
            )
        return channels[name]
    if ext == ".npy":
        return _read_npy(p)
    return _read_png_mm(p)


def _read_npy(p: Path) -> np.ndarray:
    try:
        a = np.load(p, allow_pickle=False)  # never unpickle a user-supplied file
    except Exception as e:
        raise InputFileError(p, f"cannot be read as a .npy array: {e}") from e
    if not isinstance(a, np.ndarray) or a.dtype.kind not in "fiu":
        raise InputFileError(p, f"depth .npy must hold a real-valued array, got dtype {a.dtype}")
    if a.ndim == 3 and a.shape[2] == 1:
        a = a[..., 0]
    if a.ndim != 2:
        raise InputFileError(
            p, f"depth .npy must be an (H, W) array, got shape {a.shape}", "save depth[..., 0]"
        )
    return a.astype(np.float32)


def _read_png_mm(p: Path) -> np.ndarray:
    from PIL import Image, UnidentifiedImageError

    try:
        with Image.open(p) as im:
            mode = im.mode
            a = np.array(im)
    except (UnidentifiedImageError, OSError, SyntaxError) as e:
        raise InputFileError(p, f"cannot be read as a PNG image: {e}") from e
    # Pillow opens 16-bit grayscale PNGs as "I;16" (uint16) or, in older versions, "I" (int32).
    if mode not in ("I;16", "I;16B", "I;16L", "I"):
        raise InputFileError(
            p,
            f"depth PNG must be 16-bit grayscale in millimetres, got PIL mode {mode!r} "
            "(8-bit or colour PNGs cannot hold metric depth)",
            "save depth as a 16-bit PNG (uint16 millimetres), .npy or .exr",
        )
    return (a.astype(np.float64) / 1000.0).astype(np.float32)


def write_depth_png(path: str | os.PathLike, depth_m) -> None:
    """Write (H, W) depth in metres as a 16-bit grayscale PNG in millimetres (rounded).

    Raises:
        ValueError: non-finite or negative depth, or depth above 65.535 m (use .exr/.npy).
    """
    from PIL import Image

    d = np.asarray(as_numpy_map(depth_m, "depth"), dtype=np.float64)
    if not np.isfinite(d).all():
        raise ValueError("write_depth_png: depth has NaN/inf values, which a PNG cannot hold")
    if (d < 0).any():
        raise ValueError("write_depth_png: depth has negative values")
    if d.max(initial=0.0) > PNG_MAX_DEPTH_M + 0.0005:
        raise ValueError(
            f"write_depth_png: depth up to {d.max():.3f} m exceeds the 16-bit millimetre PNG "
            f"range ({PNG_MAX_DEPTH_M} m); write .exr or .npy instead"
        )
    mm = np.minimum(np.rint(d * 1000.0), 65535).astype(np.uint16)
    Image.fromarray(mm).save(os.fspath(path), format="PNG")


def write_depth(path: str | os.PathLike, depth_m) -> None:
    """Write (H, W) depth in metres; the format follows the extension.

    ``.exr``: float32 channel ``Z``; ``.npy``: float32 array; ``.png``: 16-bit millimetres
    (see :func:`write_depth_png`). Accepts numpy arrays or torch tensors ((H, W), (1, H, W),
    (1, 1, H, W)).
    """
    ext = Path(path).suffix.lower()
    d = np.asarray(as_numpy_map(depth_m, "depth"), dtype=np.float32)
    if ext == ".exr":
        write_exr(path, {DEPTH_CHANNEL: d})
    elif ext == ".npy":
        np.save(path, d, allow_pickle=False)
    elif ext == ".png":
        write_depth_png(path, d)
    else:
        raise ValueError(
            f"write_depth: unsupported extension {ext!r} for {path}; use one of "
            f"{', '.join(DEPTH_EXTENSIONS)}"
        )
