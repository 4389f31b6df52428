"""HDR radiance + radial depth panoramas: the :class:`Panorama` record, its files, and
exposure calibration (docs/conventions.md).

Accepted inputs of :func:`read_panorama`:

(a) our EXR: channels ``R, G, B`` (half or float, linear Rec.709) and ``Z`` (float32 radial
    depth, metres), metadata as JSON in the string attribute ``roomlight``;
(b) the paper authors' 4-channel EXR: ``R, G, B, A`` with the depth in ``A`` and no ``Z``;
(c) a radiance-only EXR (``R, G, B``) or Radiance ``.hdr``, with an optional separate depth
    file (``.exr``, ``.npy`` or 16-bit PNG in millimetres; see :mod:`roomlight.core.io.depth`).

An explicit ``depth_path`` always wins over depth stored in the panorama file (a warning says
which channel was ignored). Everything read is validated (:mod:`roomlight.core.io.validate`);
repairs happen only when asked for and are listed in :attr:`Panorama.fixes`.
"""

from __future__ import annotations

import json
import math
import os
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from roomlight.core.color import LOG_EPS, luminance_np, luminance_torch
from roomlight.core.io.depth import read_depth
from roomlight.core.io.exr import DEPTH_CHANNEL, read_exr_with_header, write_exr
from roomlight.core.io.jsonable import json_default
from roomlight.errors import InputFileError, ShapeError
from roomlight.core.io.rgbe import read_hdr_with_header
from roomlight.core.io.validate import (
    as_numpy_image,
    as_numpy_map,
    check_depth_values,
    check_equirect_aspect,
    check_extension,
    check_file,
    check_finite_radiance,
    check_nonnegative_radiance,
    check_same_size,
    is_torch_tensor,
)

__all__ = [
    "Panorama",
    "PANORAMA_EXTENSIONS",
    "METADATA_ATTRIBUTE",
    "EXPOSURE_FACTOR_KEY",
    "read_panorama",
    "write_panorama",
    "luminance",
    "exposure_calibrate",
    "exposure_uncalibrate",
    "calibrate_panorama",
]

PANORAMA_EXTENSIONS = (".exr", ".hdr", ".pic")
#: EXR string attribute holding the panorama's metadata as JSON.
METADATA_ATTRIBUTE = "roomlight"
#: Metadata key of the exposure calibration factor: original radiance = stored * factor.
EXPOSURE_FACTOR_KEY = "exposure_factor"


@dataclass
class Panorama:
    """An equirectangular HDR panorama with optional radial depth.

    Attributes:
        radiance: (H, W, 3) float32 linear Rec.709 RGB, unbounded, W = 2H, row 0 = zenith.
        depth: (H, W) float32 radial distance from the capture point in metres, or None.
        metadata: JSON-serialisable dict stored with the file (e.g. ``exposure_factor``).
        path: the file it was read from, if any.
        fixes: human-readable repairs applied while reading (e.g. "clamped 3 pixels with
            negative radiance to 0"); empty when the data is exactly what the file holds.
    """

    radiance: np.ndarray
    depth: np.ndarray | None = None
    metadata: dict = field(default_factory=dict)
    path: Path | None = None
    fixes: list[str] = field(default_factory=list)

    def __post_init__(self) -> None:
        if self.radiance.ndim != 3 or self.radiance.shape[2] != 3:
            raise ShapeError(f"Panorama.radiance must be (H, W, 3), got {self.radiance.shape}")
        if self.depth is not None and self.depth.shape != self.radiance.shape[:2]:
            raise ShapeError(
                f"Panorama.depth must be (H, W) = {self.radiance.shape[:2]}, got {self.depth.shape}"
            )

    @property
    def height(self) -> int:
        return int(self.radiance.shape[0])

    @property
    def width(self) -> int:
        return int(self.radiance.shape[1])


# --------------------------------------------------------------------------------------------
# Reading


def read_panorama(
    path: str | os.PathLike,
    depth_path: str | os.PathLike | None = None,
    *,
    clamp_negative: bool = False,
    fill_nonfinite: float | None = None,
) -> Panorama:
    """Read and validate a panorama (formats (a)-(c) of the module docstring).

    Args:
        path: ``.exr`` or ``.hdr``/``.pic`` panorama.
        depth_path: optional separate depth file; overrides depth stored in ``path``.
        clamp_negative: clamp negative radiance to 0 instead of raising (reported in
            ``fixes`` and as a warning).
        fill_nonfinite: replace NaN/inf radiance by this value instead of raising (reported).
            Depth is never repaired: invalid depth always raises.
    Returns:
        A :class:`Panorama` with float32 arrays.
    Raises:
        InputFileError: missing/corrupt file, unsupported extension or channels, W != 2H,
            NaN/inf or negative radiance (unless repaired), zero/negative/non-finite depth,
            depth size different from the radiance size.
    """
    p = check_file(path)
    ext = check_extension(p, PANORAMA_EXTENSIONS, "panorama")
    metadata: dict = {}
    depth = None
    depth_source = p
    if ext == ".exr":
        radiance, depth, metadata = _read_panorama_exr(p, ignore_depth=depth_path is not None)
    else:
        radiance, header = read_hdr_with_header(p)
        if header["exposure"] != 1.0:
            # Radiance semantics: stored = true * EXPOSURE. We keep values as stored (like
            # Mitsuba) but keep the factor so it is not lost.
            metadata["hdr_exposure"] = header["exposure"]

    if depth_path is not None:
        depth_source = check_file(depth_path)
        depth = read_depth(depth_source)

    h, w = radiance.shape[:2]
    check_equirect_aspect(p, h, w)
    fixes: list[str] = []
    radiance = check_finite_radiance(p, radiance, fill=fill_nonfinite, fixes=fixes)
    radiance = check_nonnegative_radiance(p, radiance, clamp=clamp_negative, fixes=fixes)
    if depth is not None:
        check_same_size(depth_source, depth.shape, radiance.shape, p)
        check_depth_values(depth_source, depth)
        depth = np.ascontiguousarray(depth, dtype=np.float32)
    return Panorama(
        radiance=np.ascontiguousarray(radiance, dtype=np.float32),
        depth=depth,
        metadata=metadata,
        path=p,
        fixes=fixes,
    )


def _read_panorama_exr(p: Path, ignore_depth: bool):
    channels, header = read_exr_with_header(p)
    missing = [c for c in "RGB" if c not in channels]
    if missing:
        raise InputFileError(
            p,
            f"panorama EXR needs channels R, G, B; missing {', '.join(missing)} "
            f"(found {', '.join(sorted(channels))})",
            "write linear RGB radiance to channels named R, G, B",
        )
    radiance = np.stack([channels["R"], channels["G"], channels["B"]], axis=-1)
    # Our layout keeps depth in Z; the authors' 4-channel files keep it in A (and have no Z).
    depth_channel = DEPTH_CHANNEL if DEPTH_CHANNEL in channels else "A" if "A" in channels else None
    depth = None
    if depth_channel is not None:
        if ignore_depth:
            warnings.warn(
                f"{p}: ignoring depth channel {depth_channel!r} because a separate depth file "
                "was given",
                UserWarning,
                stacklevel=3,  # _read_panorama_exr <- read_panorama <- the user's call
            )
        else:
            depth = channels[depth_channel]
    metadata = _parse_metadata(p, header.get(METADATA_ATTRIBUTE))
    return radiance, depth, metadata


def _parse_metadata(p: Path, text) -> dict:
    if text is None:
        return {}
    if isinstance(text, bytes):
        text = text.decode("utf-8")
    try:
        meta = json.loads(text)
    except (TypeError, ValueError) as e:
        raise InputFileError(
            p, f"header attribute {METADATA_ATTRIBUTE!r} is not valid JSON: {e}"
        ) from e
    if not isinstance(meta, dict):
        raise InputFileError(
            p,
            f"header attribute {METADATA_ATTRIBUTE!r} must hold a JSON object, "
            f"got {type(meta).__name__}",
        )
    return meta


# --------------------------------------------------------------------------------------------
# Writing


def write_panorama(
    path: str | os.PathLike,
    pano_or_arrays,
    *,
    half: bool = True,
    metadata: dict | None = None,
) -> None:
    """Write a panorama EXR: ``R, G, B`` (float16 if ``half``, else float32), ``Z`` (float32).

    Args:
        path: output ``.exr`` file.
        pano_or_arrays: a :class:`Panorama`; or a tuple ``(radiance, depth_or_None)``; or a
            radiance array alone. Radiance is numpy (H, W, 3) or torch (3, H, W) /
            (1, 3, H, W); depth numpy/torch (H, W) (or with leading/trailing singleton dims),
            metres.
        half: store radiance as float16 (halves the file; relative precision ~5e-4, range
            up to 65504; larger values raise, use ``half=False``).
        metadata: merged over the panorama's own metadata, stored as JSON in the EXR string
            attribute ``roomlight``. Numpy scalars/arrays are converted to plain JSON.
    Raises:
        ValueError: extension other than .exr, or radiance beyond the float16 range with
            ``half=True``.
        ShapeError: wrong shapes, W != 2H, or depth/radiance size mismatch.
    """
    if Path(path).suffix.lower() != ".exr":
        raise ValueError(
            f"write_panorama: {path} must end in .exr (use roomlight.core.io.write_hdr for "
            "radiance-only .hdr files)"
        )
    if isinstance(pano_or_arrays, Panorama):
        radiance, depth = pano_or_arrays.radiance, pano_or_arrays.depth
        meta = dict(pano_or_arrays.metadata)
    elif isinstance(pano_or_arrays, (tuple, list)):
        if len(pano_or_arrays) != 2:
            raise ValueError("write_panorama: expected a (radiance, depth) pair")
        radiance, depth = pano_or_arrays
        meta = {}
    else:
        radiance, depth, meta = pano_or_arrays, None, {}
    meta.update(metadata or {})

    rad = as_numpy_image(radiance, 3, "radiance")
    h, w = rad.shape[:2]
    if w != 2 * h:
        raise ShapeError(
            f"write_panorama: radiance is {h}x{w} (H x W); an equirectangular panorama needs "
            f"width = 2 x height"
        )
    channels = {"R": rad[..., 0], "G": rad[..., 1], "B": rad[..., 2]}
    if depth is not None:
        d = as_numpy_map(depth, "depth")
        if d.shape != (h, w):
            raise ShapeError(f"write_panorama: depth is {d.shape}, radiance is {(h, w)}")
        channels[DEPTH_CHANNEL] = d
    attributes = {METADATA_ATTRIBUTE: json.dumps(meta, sort_keys=True, default=json_default)}
    write_exr(path, channels, half={"R", "G", "B"} if half else False, attributes=attributes)




# --------------------------------------------------------------------------------------------
# Exposure calibration


def luminance(radiance):
    """Rec.709 luminance Y of linear RGB.

    Args:
        radiance: numpy (..., 3) channel-last, or torch (..., 3, H, W) channel-first.
    Returns:
        numpy (...) or torch (..., H, W), same dtype family as the input.
    """
    if is_torch_tensor(radiance):
        if radiance.dim() < 3 or radiance.shape[-3] != 3:
            raise ShapeError(
                f"luminance: expected a torch tensor (..., 3, H, W), got {tuple(radiance.shape)}"
            )
        return luminance_torch(radiance)
    a = np.asarray(radiance)
    if a.shape[-1] != 3:
        raise ShapeError(f"luminance: expected a numpy array (..., 3), got {a.shape}")
    return luminance_np(a)


def exposure_calibrate(radiance):
    """Scale a panorama so that its log-average luminance is 1 (docs/conventions.md).

    ``factor = exp(mean(log(Y + 1e-6)))`` over all pixels (unweighted), computed in float64;
    returns ``(radiance / factor, factor)``. Undo with :func:`exposure_uncalibrate`.

    Args:
        radiance: numpy (H, W, 3) or torch (3, H, W) / (1, 3, H, W), linear RGB, >= 0.
    Returns:
        ``(calibrated, factor)``: same type, shape and dtype as the input; factor a float.
    """
    if is_torch_tensor(radiance):
        mean_log = float((luminance(radiance.double()) + LOG_EPS).log().mean())
    else:
        y = luminance(np.asarray(radiance, dtype=np.float64))
        mean_log = float(np.mean(np.log(y + LOG_EPS)))
    factor = math.exp(mean_log)
    if not math.isfinite(factor) or factor <= 0:
        raise ValueError(
            f"exposure_calibrate: invalid calibration factor {factor} (NaN/inf in the input?)"
        )
    return radiance / factor, factor


def exposure_uncalibrate(calibrated, factor: float):
    """Inverse of :func:`exposure_calibrate`: ``calibrated * factor`` (numpy or torch)."""
    return calibrated * factor


def calibrate_panorama(pano: Panorama) -> Panorama:
    """A copy of ``pano`` with calibrated radiance and ``metadata['exposure_factor']`` set.

    Factors compose: if ``pano`` was already calibrated, the stored factor is the product, so
    ``radiance * metadata['exposure_factor']`` is always the radiance of the original file.
    """
    calibrated, factor = exposure_calibrate(pano.radiance)
    meta = dict(pano.metadata)
    meta[EXPOSURE_FACTOR_KEY] = float(meta.get(EXPOSURE_FACTOR_KEY, 1.0)) * factor
    return Panorama(
        radiance=calibrated.astype(np.float32, copy=False),
        depth=pano.depth,
        metadata=meta,
        path=pano.path,
        fixes=list(pano.fixes),
    )
