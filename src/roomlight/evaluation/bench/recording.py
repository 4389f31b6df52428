"""The benchmark camera: exposure rule and 8-bit recording with saturation.

Exposure rule (auto-exposure on the objects, "middle grey"): the camera scales the linear
render of the input view by

    k = key / exp(mean over object pixels of log(Y + 1e-6)),    key = 0.18,

Y the Rec.709 luminance, so that the objects' log-average luminance records as middle grey.
The benchmark bakes ``k`` into the ground truth (the emitter radiance and both views' HDR
renders are multiplied by it; rendering is linear in the emitter), so the recording camera is
calibrated: its 8-bit image is

    ldr = round(255 * clip(hdr, 0, 1) ** (1 / 2.2))

with no further scale. Highlights above 1 saturate at 255, as on a camera; a fit linearises
the 8-bit image with ``x ** 2.2`` (:func:`roomlight.fitting.scene.build.load_view_target`).
"""

from __future__ import annotations

import numpy as np

from roomlight.core.color import DISPLAY_GAMMA, MIDDLE_GREY, display_to_uint8, log_average_np, to_display
from roomlight.errors import RoomlightError

__all__ = ["EXPOSURE_KEY", "SATURATION_TAU", "exposure_for", "record_ldr", "saturated_fraction"]

#: Log-average luminance the objects are exposed to.
EXPOSURE_KEY = MIDDLE_GREY
#: A recorded pixel whose largest *linearised* channel ((v / 255) ** 2.2) reaches this counts as
#: saturated (the fitting's censoring threshold, tau = 0.99).
SATURATION_TAU = 0.99


def _np(x) -> np.ndarray:
    if hasattr(x, "detach"):
        x = x.detach().cpu().numpy()
    return np.asarray(x, dtype=np.float64)


def exposure_for(hdr, mask, key: float = EXPOSURE_KEY) -> float:
    """Camera exposure ``k`` that maps the mask pixels' log-average luminance to ``key``.

    Args:
        hdr: (H, W, 3) linear render; mask: (H, W) bool object pixels.
    Returns:
        k > 0 (a plain float).
    """
    x = _np(hdr)
    m = _np(mask).astype(bool)
    if not m.any():
        raise RoomlightError("exposure: the object mask is empty; nothing to meter on")
    k = key / log_average_np(x[m])
    if not np.isfinite(k) or k <= 0:
        raise RoomlightError(f"exposure: cannot meter the objects (log-average luminance gives k = {k})")
    return k


def record_ldr(hdr, gamma: float = DISPLAY_GAMMA) -> np.ndarray:
    """8-bit recording of a linear image already at the camera's exposure.

    Args:
        hdr: (H, W, 3) linear radiance.
    Returns:
        (H, W, 3) uint8 ``round(255 * clip(hdr, 0, 1) ** (1 / gamma))``.
    """
    return display_to_uint8(to_display(_np(hdr), gamma))


def saturated_fraction(ldr: np.ndarray, mask, tau: float = SATURATION_TAU, gamma: float = DISPLAY_GAMMA) -> float:
    """Fraction of mask pixels of an 8-bit image whose largest linearised channel is >= ``tau``."""
    m = _np(mask).astype(bool)
    if not m.any():
        return 0.0
    top = (np.asarray(ldr)[m].max(axis=-1).astype(np.float64) / 255.0) ** gamma
    return float(np.mean(top >= tau))
