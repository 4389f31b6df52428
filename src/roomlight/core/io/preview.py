"""Previews: tone mapping of HDR radiance and colour-mapping of depth to 8-bit PNGs.

Inputs are numpy arrays in channel-last layout ((H, W, 3) radiance, (H, W) depth) or torch
tensors in channel-first layout ((3, H, W) / (1, 3, H, W), (H, W) / (1, H, W) / (1, 1, H, W)),
following the project's conventions (docs/conventions.md). Outputs are numpy.

The Reinhard operator here is the *extended* global operator of Reinhard et al. 2002
("Photographic tone reproduction for digital images", eq. 4) applied to luminance:

    L_d = L (1 + L / L_white^2) / (1 + L)

and colour is carried by scaling RGB with L_d / L. It maps L_white to exactly 1 and is
strictly increasing, so it has a closed-form inverse (a quadratic in L), given here too.
"""

from __future__ import annotations

import os

import numpy as np

from roomlight.core.color import DISPLAY_GAMMA, MIDDLE_GREY, display_to_uint8
from roomlight.core.io.panorama import luminance
from roomlight.core.io.validate import as_numpy_image, as_numpy_map

__all__ = [
    "tonemap_gamma",
    "auto_exposure_stops",
    "reinhard_extended",
    "inverse_reinhard_extended",
    "colorize_depth",
    "save_png",
    "save_radiance_preview",
]


def _radiance(x) -> np.ndarray:
    return np.asarray(as_numpy_image(x, 3, "radiance"), dtype=np.float64)


def tonemap_gamma(radiance, exposure_stops: float = 0.0, gamma: float = DISPLAY_GAMMA) -> np.ndarray:
    """Exposure, clip to [0, 1] and gamma-encode: ``(x * 2**stops) ** (1 / gamma)``.

    Args:
        radiance: (H, W, 3) linear RGB (or torch (3, H, W)); NaN/inf show as black/white.
    Returns:
        (H, W, 3) uint8.
    """
    x = _radiance(radiance) * (2.0 ** exposure_stops)
    # NaN -> 0 so that a broken pixel is visible as black rather than crashing the cast.
    x = np.nan_to_num(x, nan=0.0, posinf=1.0, neginf=0.0)
    return display_to_uint8(np.clip(x, 0.0, 1.0) ** (1.0 / gamma))


def auto_exposure_stops(radiance, key: float = MIDDLE_GREY, mask=None) -> float:
    """Exposure (stops) that maps the log-average luminance of ``radiance`` to ``key``.

    A camera's auto-exposure: with ``tonemap_gamma(x, auto_exposure_stops(x))`` walls and
    objects land around middle grey and only light sources clip. ``mask`` ((H, W) bool)
    restricts the average to some pixels (e.g. the objects of a render); pixels of zero
    luminance (background, black bodies) are left out so they do not drag the average down.
    """
    y = luminance(_radiance(radiance))
    keep = np.isfinite(y) & (y > 0)
    if mask is not None:
        keep &= np.asarray(mask, bool)
    if not keep.any():
        return 0.0
    return float(np.log2(key) - np.mean(np.log2(y[keep])))


def reinhard_extended(radiance, white: float | None = None) -> np.ndarray:
    """Reinhard 2002 extended operator on luminance (see the module docstring).

    Args:
        radiance: (H, W, 3) linear RGB (or torch (3, H, W)).
        white: luminance mapped to 1 (``L_white``); defaults to the image's maximum luminance.
            Keep it (e.g. ``luminance(x).max()``) if you want to invert the mapping later.
    Returns:
        (H, W, 3) float64 tone-mapped linear RGB (luminance in [0, 1] for L <= white).
        Pixels with luminance <= 0 are passed through unchanged.
    """
    x = _radiance(radiance)
    lum = luminance(x)
    if white is None:
        white = float(lum.max()) if lum.size else 1.0
    if not white > 0:
        raise ValueError(f"reinhard_extended: white must be > 0, got {white}")
    pos = lum > 0
    ld = np.where(pos, lum * (1.0 + lum / white**2) / (1.0 + np.where(pos, lum, 0.0)), lum)
    scale = np.where(pos, ld / np.where(pos, lum, 1.0), 1.0)
    return x * scale[..., None]


def inverse_reinhard_extended(tonemapped, white: float) -> np.ndarray:
    """Exact inverse of :func:`reinhard_extended` for the same ``white``.

    Solves ``L^2 / w^2 + L (1 - L_d) - L_d = 0`` for the positive root, written as
    ``L = 2 L_d / ((1 - L_d) + sqrt((1 - L_d)^2 + 4 L_d / w^2))`` to avoid the cancellation
    of the textbook formula when ``w`` is large. ``white = inf`` gives plain Reinhard's
    inverse ``L_d / (1 - L_d)``.

    Args:
        tonemapped: (H, W, 3) output of :func:`reinhard_extended` (or torch (3, H, W)).
        white: the white point used for the forward mapping.
    Returns:
        (H, W, 3) float64 linear RGB.
    """
    y = _radiance(tonemapped)
    if not white > 0:
        raise ValueError(f"inverse_reinhard_extended: white must be > 0, got {white}")
    ld = luminance(y)
    pos = ld > 0
    ldp = np.where(pos, ld, 0.5)  # placeholder for pass-through pixels, keeps the maths finite
    one_minus = 1.0 - ldp
    lum = 2.0 * ldp / (one_minus + np.sqrt(one_minus**2 + 4.0 * ldp / white**2))
    scale = np.where(pos, lum / ldp, 1.0)
    return y * scale[..., None]


def colorize_depth(
    depth,
    vmin: float | None = None,
    vmax: float | None = None,
    cmap: str = "turbo",
    log: bool = False,
) -> np.ndarray:
    """Colour-map a depth map for viewing.

    Args:
        depth: (H, W) metres (or torch (1, H, W) / (1, 1, H, W)).
        vmin, vmax: range mapped to the ends of the colour map, metres; default to the min /
            max of the valid (finite, and > 0 when ``log``) values.
        cmap: any matplotlib colour map name.
        log: map log(depth) instead of depth (indoor depth spans ~0.3-30 m; log spreads it).
    Returns:
        (H, W, 3) uint8; invalid pixels (NaN/inf, or <= 0 with ``log``) are black.
    """
    import matplotlib

    d = np.asarray(as_numpy_map(depth, "depth"), dtype=np.float64)
    valid = np.isfinite(d) & ((d > 0) if log else True)
    if vmin is None:
        vmin = float(d[valid].min()) if valid.any() else 0.0
    if vmax is None:
        vmax = float(d[valid].max()) if valid.any() else 1.0
    if log:
        if vmin <= 0 or vmax <= 0:
            raise ValueError(f"colorize_depth: log scale needs vmin, vmax > 0, got {vmin}, {vmax}")
        f = lambda v: np.log(v)  # noqa: E731
    else:
        f = lambda v: v  # noqa: E731
    lo, hi = f(vmin), f(vmax)
    span = hi - lo if hi > lo else 1.0
    t = np.zeros_like(d)
    t[valid] = np.clip((f(d[valid]) - lo) / span, 0.0, 1.0)
    rgb = matplotlib.colormaps[cmap](t)[..., :3]
    out = display_to_uint8(rgb)
    out[~valid] = 0
    return out


def save_png(path: str | os.PathLike, image: np.ndarray) -> None:
    """Write an (H, W, 3), (H, W, 4) or (H, W) uint8 image as PNG."""
    from PIL import Image

    a = np.asarray(image)
    if a.dtype != np.uint8:
        raise ValueError(
            f"save_png: expected uint8 (use tonemap_gamma/colorize_depth), got {a.dtype}"
        )
    if not (a.ndim == 2 or (a.ndim == 3 and a.shape[2] in (3, 4))):
        raise ValueError(f"save_png: expected (H, W), (H, W, 3) or (H, W, 4), got {a.shape}")
    Image.fromarray(np.ascontiguousarray(a)).save(os.fspath(path), format="PNG")


def save_radiance_preview(
    path: str | os.PathLike,
    radiance,
    *,
    exposure_stops: float = 0.0,
    gamma: float = DISPLAY_GAMMA,
    operator: str = "gamma",
    white: float | None = None,
) -> np.ndarray:
    """Tone-map radiance and save it as PNG; returns the (H, W, 3) uint8 image written.

    Args:
        operator: ``"gamma"`` (exposure, clip, gamma) or ``"reinhard"`` (exposure, then
            :func:`reinhard_extended` with ``white``, then gamma).
    """
    if operator == "gamma":
        img = tonemap_gamma(radiance, exposure_stops, gamma)
    elif operator == "reinhard":
        x = _radiance(radiance) * (2.0 ** exposure_stops)
        img = tonemap_gamma(reinhard_extended(x, white), 0.0, gamma)
    else:
        raise ValueError(
            f"save_radiance_preview: operator must be 'gamma' or 'reinhard', got {operator!r}"
        )
    save_png(path, img)
    return img
