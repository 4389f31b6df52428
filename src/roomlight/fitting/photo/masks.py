"""Object masks: which pixels belong to which object of interest.

A mask file names the objects in one of three ways (0, or black, is background everywhere):

- **binary** (a single non-zero value, e.g. 0/255 or 0/1): each 8-connected component is one object,
  numbered 1, 2, ... in reading order (by its first pixel, row by row);
- **integer labels** (two or more non-zero values: 8/16-bit grey or palette PNG, ``.npy``, ``.exr``):
  each value is one object and keeps its number, whether or not its pixels touch;
- **colours** (an RGB PNG): each distinct non-black colour is one object, numbered 1, 2, ... by
  the colour's first pixel in reading order.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from roomlight.errors import InputFileError, RoomlightError

__all__ = ["MASK_EXTENSIONS", "ObjectLabels", "read_mask", "read_mask_array", "labels_from_array", "connected_components",
           "resize_nearest", "erode"]

MASK_EXTENSIONS = (".png", ".npy", ".exr")


@dataclass
class ObjectLabels:
    """(H, W) int32 ``labels`` (0 background) and how they were read.

    Attributes:
        kind: ``binary``, ``labels``, ``colours``, or ``none`` (no mask given: no objects).
        ids: the object labels present, ascending.
        notes: human-readable remarks (e.g. objects dropped as too small).
    """

    labels: np.ndarray
    kind: str
    ids: list[int]
    notes: list[str] = field(default_factory=list)


def connected_components(foreground: np.ndarray) -> tuple[np.ndarray, int]:
    """8-connected components of a boolean (H, W) image.

    Returns (labels (H, W) int32 with 0 for background and 1..n numbered in reading order, n).
    Minimum-label propagation over the 3 x 3 neighbourhood with pointer jumping: every pixel
    holds the flat index of the smallest pixel it is known to be connected to.
    """
    fg = np.asarray(foreground, dtype=bool)
    h, w = fg.shape
    big = h * w
    lab = np.where(fg, np.arange(big).reshape(h, w), big)
    while True:
        padded = np.pad(lab, 1, constant_values=big)
        m = lab
        for dy in (0, 1, 2):
            for dx in (0, 1, 2):
                m = np.minimum(m, padded[dy:dy + h, dx:dx + w])
        m = np.where(fg, m, big).ravel()
        ext = np.append(m, big)
        while True:  # pointer jumping: follow each index to the label its target already holds
            jumped = ext[m]
            if np.array_equal(jumped, m):
                break
            m = jumped
            ext[:-1] = m
        m = m.reshape(h, w)
        if np.array_equal(m, lab):
            break
        lab = m
    roots, inverse = np.unique(lab.ravel(), return_inverse=True)  # roots ascend = reading order
    n = int((roots < big).sum())
    out = (inverse.reshape(h, w) + 1).astype(np.int32)
    out[~fg] = 0
    return out, n


def labels_from_array(values: np.ndarray, min_fraction: float = 0.0, where: str = "mask") -> ObjectLabels:
    """Object labels from a mask array: (H, W) integers, or (H, W, 3) colours.

    Objects covering less than ``min_fraction`` of the image are dropped (a note says which).
    """
    a = np.asarray(values)
    if a.ndim == 3:
        flat = a.reshape(-1, a.shape[2]).astype(np.int64)
        nonzero = flat.any(1)
        colours, first, inverse = np.unique(flat, axis=0, return_index=True, return_inverse=True)
        inverse = inverse.ravel()
        order = [k for k in np.argsort(first) if colours[k].any()]
        remap = np.zeros(len(colours), np.int32)
        for new, k in enumerate(order, start=1):
            remap[k] = new
        labels = np.where(nonzero, remap[inverse], 0).reshape(a.shape[:2]).astype(np.int32)
        kind = "colours"
    else:
        if a.dtype.kind == "f":
            if not np.isfinite(a).all():
                raise RoomlightError(f"{where}: the mask has NaN or infinite values")
            if not np.array_equal(a, np.round(a)):
                raise RoomlightError(f"{where}: mask values must be integer labels, found fractional values")
        if a.dtype.kind not in "biuf":
            raise RoomlightError(f"{where}: expected an integer label mask, got dtype {a.dtype}")
        if (a < 0).any():
            raise RoomlightError(f"{where}: mask labels must be >= 0 (0 = background), found {int(a.min())}")
        ints = a.astype(np.int64)
        values_present = np.unique(ints[ints != 0])
        if len(values_present) == 1:
            labels, _ = connected_components(ints != 0)
            kind = "binary"
        else:
            if len(values_present) and values_present.max() > np.iinfo(np.int32).max:
                raise RoomlightError(f"{where}: mask label {int(values_present.max())} is too large")
            labels = ints.astype(np.int32)
            kind = "labels"
    if not (labels != 0).any():
        raise RoomlightError(f"{where}: the mask selects no pixel (every value is 0); mark the objects of "
                             "interest with non-zero values")
    notes = []
    ids, counts = np.unique(labels[labels != 0], return_counts=True)
    small = ids[counts < min_fraction * labels.size]
    if len(small):
        labels = np.where(np.isin(labels, small), 0, labels).astype(np.int32)
        notes.append(f"{where}: ignored {len(small)} object(s) smaller than {min_fraction:.3%} of the image "
                     f"(labels {', '.join(str(int(s)) for s in small[:10])}{', ...' if len(small) > 10 else ''})")
        if not (labels != 0).any():
            raise RoomlightError(f"{where}: every object is smaller than {min_fraction:.3%} of the image; "
                                 "nothing is left to fit")
    kept = [int(i) for i in np.unique(labels[labels != 0])]
    return ObjectLabels(labels, kind, kept, notes)


def read_mask_array(path) -> np.ndarray:
    """The raw content of a mask file (``.png``, ``.npy`` or ``.exr``): (H, W) values or (H, W, 3) colours."""
    p = Path(path)
    if not p.is_file():
        raise InputFileError(p, "mask file does not exist" if not p.exists() else "is not a regular file")
    ext = p.suffix.lower()
    if ext not in MASK_EXTENSIONS:
        raise InputFileError(p, f"unsupported mask format {ext or '(none)'}; expected one of {', '.join(MASK_EXTENSIONS)}",
                             "a lossy JPEG cannot hold exact labels: save the mask as PNG")
    try:
        if ext == ".npy":
            a = np.load(p, allow_pickle=False)
            if a.ndim == 3 and a.shape[2] == 1:
                a = a[..., 0]
        elif ext == ".exr":
            from roomlight.core.io import read_exr

            ch = read_exr(p)
            if len(ch) != 1:
                names = [n for n in ("Y", "R", "Z") if n in ch]
                if not names:
                    raise InputFileError(p, f"expected one channel of labels, found {', '.join(ch)}")
                a = ch[names[0]]
            else:
                a = next(iter(ch.values()))
        else:
            a = _read_png(p)
    except InputFileError:
        raise
    except Exception as exc:
        raise InputFileError(p, f"cannot read the mask ({str(exc).splitlines()[0] if str(exc) else type(exc).__name__})") from None
    if a.ndim not in (2, 3) or (a.ndim == 3 and a.shape[2] != 3):
        raise InputFileError(p, f"expected an (H, W) label array or an RGB image, got shape {a.shape}")
    return a


def read_mask(path, min_fraction: float = 0.0) -> ObjectLabels:
    """Read a mask file (``.png``, ``.npy`` or ``.exr``) into object labels (module docstring)."""
    return labels_from_array(read_mask_array(path), min_fraction, where=str(path))


def _read_png(p: Path) -> np.ndarray:
    from PIL import Image

    with Image.open(p) as im:
        mode = im.mode
        if mode in ("RGB", "RGBA"):
            return np.asarray(im.convert("RGB"))
        if mode in ("LA",):
            return np.asarray(im.convert("L"))
        if mode == "P":  # palette indices are the labels
            return np.asarray(im)
        if mode == "1":
            return np.asarray(im).astype(np.uint8)
        return np.asarray(im)


def resize_nearest(a: np.ndarray, height: int, width: int) -> np.ndarray:
    """Nearest-neighbour resampling at pixel centres: output pixel (i, j) takes the input pixel
    under its centre, so labels and depth values are never mixed."""
    h, w = a.shape[:2]
    rows = np.minimum(((np.arange(height) + 0.5) * h / height).astype(np.int64), h - 1)
    cols = np.minimum(((np.arange(width) + 0.5) * w / width).astype(np.int64), w - 1)
    return a[rows][:, cols]


def erode(mask: np.ndarray, steps: int = 1) -> np.ndarray:
    """Binary erosion with a 3 x 3 square, ``steps`` times; pixels beyond the border count as outside."""
    m = np.asarray(mask, dtype=bool)
    h, w = m.shape
    for _ in range(steps):
        p = np.pad(m, 1, constant_values=False)
        out = np.ones_like(m)
        for dy in (0, 1, 2):
            for dx in (0, 1, 2):
                out &= p[dy:dy + h, dx:dx + w]
        m = out
    return m
