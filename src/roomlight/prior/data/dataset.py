"""The training dataset: a folder of panorama EXRs at the training resolution (docs/training.md).

Each item is one panorama as the prior sees it before normalisation: linear radiance, exposure
calibrated (docs/conventions.md), and radial depth, both resampled to the training resolution.
Accepted files are roomlight's EXRs (``R, G, B, Z``) and the paper authors' 4-channel EXRs
(``R, G, B, A`` with depth in ``A``), read through :func:`roomlight.core.io.read_panorama`.

A file that cannot be used (corrupt, no depth, W != 2H, NaN, ...) never stops an epoch: the item
comes back as ``{"name", "index", "error"}``, and :func:`collate_panoramas` drops it from the
batch and lists it under ``"skipped"`` so the caller can report it by name.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import torch
from torch.utils.data import Dataset

from roomlight.errors import InputFileError, RoomlightError

__all__ = ["DEPTH_UNITS", "load_training_pair", "encode_pair", "decode_pair", "PanoramaDataset",
           "collate_panoramas"]

#: How depth is scaled for training: ``metres`` as stored (roomlight datasets), or
#: ``scale-free`` = divided by its geometric mean (the authors' convention).
DEPTH_UNITS = ("metres", "scale-free")


def load_training_pair(path: str | Path, resolution: tuple[int, int], calibrate: bool = True,
                       depth_units: str = "metres", depth_path: str | Path | None = None,
                       require_depth: bool = True, *, clamp_negative: bool = False,
                       fill_nonfinite: float | None = None) -> tuple[torch.Tensor, torch.Tensor | None, dict]:
    """Read one panorama and bring it to the training format.

    Args:
        path: panorama EXR with depth (channel ``Z``, or ``A`` in the authors' layout), or a
            radiance-only ``.exr``/``.hdr`` with ``depth_path``.
        resolution: (H, W) training resolution, W = 2 H.
        calibrate: divide radiance by exp(mean log(Y + 1e-6)) (at the file's own resolution) so
            its log-average luminance is 1; already calibrated files are unaffected (factor 1).
        depth_units: ``metres`` (keep) or ``scale-free`` (divide by the geometric mean).
        depth_path: separate depth file (``.exr``, ``.npy``, 16-bit PNG in mm).
        require_depth: raise when there is no depth; otherwise depth comes back as None.
        clamp_negative, fill_nonfinite: repairs of the radiance, as for
            :func:`roomlight.core.io.read_panorama`; without them such a file is refused.
    Returns:
        radiance (3, H, W) float32 linear >= 0; depth (1, H, W) float32 > 0 (or None); info dict
        with ``exposure_factor`` (original = returned * factor), ``depth_scale`` (original depth
        = returned * scale), the source ``resolution`` and ``fixes`` (one line per repair).
    Raises:
        InputFileError: the file cannot be read or has no depth (the message names the file).
    """
    from roomlight.core.geometry.resample import resize_panorama
    from roomlight.core.io import exposure_calibrate, read_panorama

    if depth_units not in DEPTH_UNITS:
        raise RoomlightError(f"depth_units must be one of {DEPTH_UNITS}, got {depth_units!r}")
    import warnings

    with warnings.catch_warnings():  # repairs are returned in info["fixes"] for the caller to report
        warnings.simplefilter("ignore")
        pano = read_panorama(path, depth_path=depth_path, clamp_negative=clamp_negative,
                             fill_nonfinite=fill_nonfinite)
    if pano.depth is None and require_depth:
        raise InputFileError(path, "has no depth channel (expected Z, or A in the authors' 4-channel layout)",
                             "training needs radiance + radial depth; add depth or remove the file")
    radiance = pano.radiance.astype(np.float64)
    factor, scale = 1.0, 1.0
    if calibrate:
        radiance, factor = exposure_calibrate(radiance)
    h, w = resolution
    if w != 2 * h:
        raise RoomlightError(f"training resolution must be (H, 2H), got {resolution}")
    rad_t = torch.from_numpy(np.ascontiguousarray(radiance.transpose(2, 0, 1)))[None]
    if rad_t.shape[-2] != h:
        rad_t = resize_panorama(rad_t, h).clamp_min(0.0)
    dep_t = None
    if pano.depth is not None:
        depth = pano.depth.astype(np.float64)
        if depth_units == "scale-free":
            scale = math.exp(float(np.log(depth).mean()))
            depth = depth / scale
        dep_t = torch.from_numpy(np.ascontiguousarray(depth))[None, None]
        if dep_t.shape[-2] != h:
            # Block averaging keeps depth positive; bilinear resampling of positive values does too.
            dep_t = resize_panorama(dep_t, h)
        dep_t = dep_t[0].float().contiguous()
    info = {"exposure_factor": float(factor), "depth_scale": float(scale),
            "source_resolution": [pano.height, pano.width], "fixes": list(pano.fixes)}
    return rad_t[0].float().contiguous(), dep_t, info


def encode_pair(radiance: torch.Tensor, depth: torch.Tensor) -> torch.Tensor:
    """Pack (3, H, W) radiance and (1, H, W) depth as (4, H, W) (log1p R, G, B, log D).

    The log encoding lets the packed cache store HDR values (sun, lamps) in float16 without
    overflow, at a relative precision of about 0.4 % for the brightest pixels.
    """
    return torch.cat([torch.log1p(radiance.clamp_min(0.0)), torch.log(depth)], dim=0)


def decode_pair(x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """Inverse of :func:`encode_pair`: (4, H, W) -> radiance (3, H, W), depth (1, H, W), float32."""
    x = x.float()
    return torch.expm1(x[:3]).clamp_min(0.0), torch.exp(x[3:])


class PanoramaDataset(Dataset):
    """Panoramas of a list of files, at one training resolution.

    Args:
        files: panorama EXR paths (e.g. one split of :func:`roomlight.prior.data.splits.split_files`).
        resolution: (H, W) training resolution.
        root: folder that names are relative to (default: each file's parent).
        calibrate, depth_units, clamp_negative, fill_nonfinite: see :func:`load_training_pair`
            (a file needing a repair that is not enabled becomes an item with ``error``).
        cache: an opened :class:`~roomlight.prior.data.cache.PackedCache` holding these files; items
            are then read from it instead of decoding EXRs.
        require_depth: False accepts radiance-only files (real captures, ``.hdr``); their
            ``depth`` is None (evaluation of radiance only; training needs depth).

    Items are dicts: ``radiance`` (3, H, W) float32 linear, ``depth`` (1, H, W) float32,
    ``name`` (relative path), ``index`` (int); or ``name``, ``index``, ``error`` (str) for a
    file that cannot be used.
    """

    def __init__(self, files, resolution: tuple[int, int], root: str | Path | None = None,
                 calibrate: bool = True, depth_units: str = "metres", cache=None, *,
                 clamp_negative: bool = False, fill_nonfinite: float | None = None, require_depth: bool = True):
        self.files = [Path(f) for f in files]
        self.require_depth = require_depth
        self.resolution = (int(resolution[0]), int(resolution[1]))
        self.root = Path(root) if root is not None else None
        self.calibrate = calibrate
        self.depth_units = depth_units
        self.cache = cache
        self.repairs = {"clamp_negative": clamp_negative, "fill_nonfinite": fill_nonfinite}
        if cache is not None and tuple(cache.resolution) != self.resolution:
            raise RoomlightError(f"PanoramaDataset: cache resolution {cache.resolution} differs from "
                                 f"the requested {self.resolution}")

    def __len__(self) -> int:
        return len(self.files)

    def name(self, index: int) -> str:
        """Relative path of item ``index`` (used in messages and logs)."""
        p = self.files[index]
        if self.root is not None:
            try:
                return p.relative_to(self.root).as_posix()
            except ValueError:
                pass
        return p.name

    def __getitem__(self, index: int) -> dict:
        name = self.name(index)
        info: dict = {}
        try:
            if self.cache is not None:
                radiance, depth = decode_pair(self.cache.get(name))
            else:
                radiance, depth, info = load_training_pair(self.files[index], self.resolution,
                                                        self.calibrate, self.depth_units, **self.repairs,
                                                        require_depth=self.require_depth)
        except (RoomlightError, OSError, ValueError) as exc:
            # Reported by the collate function; one bad file must not end the epoch.
            return {"name": name, "index": index, "error": str(exc)}
        item = {"radiance": radiance, "depth": depth, "name": name, "index": index}
        if info.get("fixes"):
            item["fixes"] = info["fixes"]  # repairs the caller asked for, to be reported
        return item


def collate_panoramas(items: list[dict]) -> dict:
    """Stack good items; list the bad ones.

    Returns:
        ``radiance`` (B, 3, H, W) and ``depth`` (B, 1, H, W) (None when every item was bad;
        ``depth`` also None when an item has no depth),
        ``names`` (list of B relative paths), ``indices`` (B,) int64, and ``skipped``: a list of
        (name, reason) for the items that could not be loaded.
    """
    good = [it for it in items if "error" not in it]
    skipped = [(it["name"], it["error"]) for it in items if "error" in it]
    if not good:
        return {"radiance": None, "depth": None, "names": [], "indices": torch.zeros(0, dtype=torch.int64),
                "skipped": skipped}
    depths = [it["depth"] for it in good]
    return {
        "radiance": torch.stack([it["radiance"] for it in good]),
        # Radiance-only items (depth None) make the whole batch radiance-only.
        "depth": None if any(d is None for d in depths) else torch.stack(depths),
        "names": [it["name"] for it in good],
        "indices": torch.tensor([it["index"] for it in good], dtype=torch.int64),
        "skipped": skipped,
        "fixes": [(it["name"], fix) for it in good for fix in it.get("fixes", [])],
    }
