"""Validation of panorama inputs, and coercion of in-memory arrays to numpy.

Every check about a *file* raises :class:`roomlight.errors.InputFileError` whose message names
the file, says what is wrong (with pixel counts where that helps) and how to fix it. Checks on
in-memory arrays that a caller passed (not read from a file) raise
:class:`roomlight.errors.ShapeError` or ``ValueError``.

Repairs are never silent: the ``fix_*`` helpers only run when the caller asked for them
(``clamp_negative=True``, ``fill_nonfinite=0.0``); they append a human-readable line to a
``fixes`` list (kept on :class:`roomlight.core.io.panorama.Panorama`) and emit a ``UserWarning``.

This module is torch-free: tensors are recognised by duck typing and converted lazily, so that
reading files does not pay for importing torch.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Iterable
from pathlib import Path

import numpy as np

from roomlight.errors import InputFileError, ShapeError

__all__ = [
    "CLAMP_NEGATIVE_FIX",
    "FILL_NONFINITE_FIX",
    "check_file",
    "check_extension",
    "check_equirect_aspect",
    "check_same_size",
    "check_finite_radiance",
    "check_nonnegative_radiance",
    "check_depth_values",
    "record_fix",
    "is_torch_tensor",
    "as_numpy_image",
    "as_numpy_map",
]

# How to ask for each repair; pinned by tests and reused by the CLI help.
CLAMP_NEGATIVE_FIX = "pass clamp_negative=True / --clamp-negative to clamp them to 0"
FILL_NONFINITE_FIX = (
    "pass fill_nonfinite=0.0 / --fill-nonfinite 0 to replace them, or fix the file"
)


# --------------------------------------------------------------------------------------------
# Files


def check_file(path: str | os.PathLike) -> Path:
    """Return ``path`` as a :class:`Path` after checking that it is an existing regular file."""
    p = Path(path)
    if not p.exists():
        raise InputFileError(p, "file does not exist", "check the path and the working directory")
    if not p.is_file():
        raise InputFileError(p, "is not a regular file (a directory?)", "pass the path of a file")
    return p


def check_extension(path: str | os.PathLike, allowed: Iterable[str], what: str) -> str:
    """Return the lower-case suffix of ``path`` (e.g. ``'.exr'``) if it is in ``allowed``."""
    allowed = tuple(allowed)
    ext = Path(path).suffix.lower()
    if ext not in allowed:
        shown = f"'{ext}'" if ext else "(none)"
        raise InputFileError(
            path,
            f"unsupported file extension {shown} for a {what}; "
            f"expected one of {', '.join(allowed)}",
            "convert the file to OpenEXR (.exr), which keeps linear float values",
        )
    return ext


# --------------------------------------------------------------------------------------------
# Shapes


def check_equirect_aspect(path, height: int, width: int, what: str = "panorama") -> None:
    """Raise unless ``width == 2 * height`` (the equirectangular convention, docs/conventions.md)."""
    if height <= 0 or width != 2 * height:
        raise InputFileError(
            path,
            f"{what} is {height}x{width} (H x W) but an equirectangular panorama needs "
            f"width = 2 x height",
            f"resample it to {height}x{2 * height} (or crop/pad to a 2:1 image)",
        )


def check_same_size(depth_path, depth_shape: tuple, radiance_shape: tuple, radiance_path) -> None:
    """Raise if the depth map's (H, W) differs from the radiance's (H, W)."""
    dh, dw = depth_shape[:2]
    rh, rw = radiance_shape[:2]
    if (dh, dw) != (rh, rw):
        raise InputFileError(
            depth_path,
            f"depth map size mismatch: depth is {dh}x{dw} (H x W) but the radiance "
            f"{radiance_path} is {rh}x{rw}",
            "resample the depth map to the radiance size (nearest-neighbour, not bilinear, "
            "across depth edges)",
        )


# --------------------------------------------------------------------------------------------
# Values


def _pixels(n: int) -> str:
    return f"{n} pixel" if n == 1 else f"{n} pixels"


def record_fix(fixes: list[str] | None, path, message: str) -> None:
    """Report a repair: append it to ``fixes`` and emit a ``UserWarning`` naming the file."""
    if fixes is not None:
        fixes.append(message)
    # stacklevel 4: record_fix <- check_* <- read_panorama <- the user's call
    warnings.warn(f"{path}: {message}", UserWarning, stacklevel=4)


def check_finite_radiance(
    path, radiance: np.ndarray, fill: float | None = None, fixes: list[str] | None = None
) -> np.ndarray:
    """Check (H, W, 3) radiance for NaN/±inf; replace them with ``fill`` if it is given.

    A pixel counts once even if several of its channels are bad. Returns the (possibly
    repaired) array; the input is not modified.
    """
    bad = ~np.isfinite(radiance)
    bad_px = bad.any(axis=-1)
    n = int(bad_px.sum())
    if n == 0:
        return radiance
    if fill is None:
        n_nan = int(np.isnan(radiance).any(axis=-1).sum())
        raise InputFileError(
            path,
            f"radiance has {n} of {bad_px.size} pixels with NaN or infinite values "
            f"({n_nan} with NaN, {n - n_nan} with only +/-inf)",
            FILL_NONFINITE_FIX,
        )
    fill = float(fill)
    if not np.isfinite(fill):
        raise ValueError(f"fill_nonfinite must be a finite number, got {fill}")
    out = radiance.copy()
    out[bad] = fill
    record_fix(fixes, path, f"replaced {_pixels(n)} with NaN/infinite radiance by {fill:g}")
    return out


def check_nonnegative_radiance(
    path, radiance: np.ndarray, clamp: bool = False, fixes: list[str] | None = None
) -> np.ndarray:
    """Check finite (H, W, 3) radiance for negative values; clamp them to 0 if ``clamp``.

    Negative radiance is unphysical (it usually comes from a denoiser or from resampling with
    a sharpening filter); the model's log1p input would turn it into NaN.
    """
    neg = radiance < 0
    neg_px = neg.any(axis=-1)
    n = int(neg_px.sum())
    if n == 0:
        return radiance
    if not clamp:
        raise InputFileError(
            path,
            f"radiance has {n} of {neg_px.size} pixels with negative values "
            f"(minimum {float(radiance.min()):.4g})",
            CLAMP_NEGATIVE_FIX,
        )
    out = np.maximum(radiance, 0).astype(radiance.dtype, copy=False)
    record_fix(fixes, path, f"clamped {_pixels(n)} with negative radiance to 0")
    return out


def check_depth_values(path, depth: np.ndarray) -> None:
    """Require a finite, strictly positive (H, W) radial depth map (metres).

    Depth feeds ``log`` and places mesh vertices, so holes (0 in PNG depth, inf through
    windows) cannot be repaired by a neutral value: the user must decide what they mean.
    """
    bad = ~np.isfinite(depth)
    n_bad = int(bad.sum())
    if n_bad:
        raise InputFileError(
            path,
            f"depth has {n_bad} of {depth.size} pixels with NaN or infinite values",
            "fill holes (e.g. windows, missing returns) with a finite far distance in metres "
            "before loading",
        )
    nonpos = depth <= 0
    n = int(nonpos.sum())
    if n:
        raise InputFileError(
            path,
            f"depth has {n} of {depth.size} pixels with zero or negative values "
            f"(minimum {float(depth.min()):.4g}); depth must be the radial distance in metres, > 0",
            "fill holes (0 often marks 'no measurement') with a valid distance before loading",
        )


# --------------------------------------------------------------------------------------------
# In-memory arrays


def is_torch_tensor(x) -> bool:
    """True for a ``torch.Tensor`` (checked without importing torch)."""
    return type(x).__module__.startswith("torch") and hasattr(x, "detach")


def as_numpy_image(x, channels: int = 3, what: str = "image") -> np.ndarray:
    """Return an (H, W, C) numpy array from numpy (H, W, C) or torch (C, H, W) / (1, C, H, W).

    Layouts follow the project convention (docs/conventions.md): numpy images are channel-last,
    torch tensors channel-first. The dtype is preserved (use ``.astype`` where needed).
    """
    if is_torch_tensor(x):
        t = x.detach().cpu()
        if t.dim() == 4 and t.shape[0] == 1:
            t = t[0]
        if t.dim() != 3 or t.shape[0] != channels:
            raise ShapeError(
                f"{what}: expected a torch tensor of shape ({channels}, H, W) or "
                f"(1, {channels}, H, W), got {tuple(t.shape)}"
            )
        return _tensor_to_numpy(t.permute(1, 2, 0))
    a = np.asarray(x)
    if a.ndim != 3 or a.shape[2] != channels:
        raise ShapeError(
            f"{what}: expected a numpy array of shape (H, W, {channels}), got {a.shape}"
        )
    return a


def as_numpy_map(x, what: str = "map") -> np.ndarray:
    """Return an (H, W) numpy array from numpy (H, W) / (H, W, 1) or torch (H, W) /
    (1, H, W) / (1, 1, H, W)."""
    if is_torch_tensor(x):
        t = x.detach().cpu()
        while t.dim() > 2 and t.shape[0] == 1:
            t = t[0]
        if t.dim() != 2:
            raise ShapeError(
                f"{what}: expected a torch tensor of shape (H, W), got {tuple(x.shape)}"
            )
        return _tensor_to_numpy(t)
    a = np.asarray(x)
    if a.ndim == 3 and a.shape[2] == 1:
        a = a[..., 0]
    if a.ndim != 2:
        raise ShapeError(f"{what}: expected a numpy array of shape (H, W), got {a.shape}")
    return a


def _tensor_to_numpy(t) -> np.ndarray:
    """CPU tensor -> numpy; bfloat16 (no numpy equivalent) is widened to float32."""
    import torch  # already imported by whoever made the tensor, so this is free

    if t.dtype == torch.bfloat16:
        t = t.float()
    return t.numpy()
