"""Benchmark metrics over object pixels (paper §4.2 "Metrics", supplementary "Rendering").

All three compare a render under a recovered emitter with the ground-truth render of the same
view, over the pixels of a mask (the probe sphere in the evaluation view, the two objects in the
input view). Images are (H, W, 3) linear RGB in the recording camera's units (the benchmark
applies the camera exposure to the ground truth, see ``docs/benchmark.md``), so no further
exposure is applied here.

- :func:`psnr_ldr`: gamma 2.2 and clip to [0, 1] (``clip(x, 0, 1) ** (1 / 2.2)``), then
  ``10 log10(1 / MSE)`` with the MSE averaged over mask pixels and the three channels.
- :func:`rmse_hdr`: ``sqrt(MSE)`` on linear radiance, over mask pixels and channels.
- :func:`angular_error_deg`: per pixel, the angle between the two RGB vectors in degrees,
  averaged over mask pixels (LeGendre et al. 2019). A pixel where exactly one of the two is
  black counts 90 degrees; where both are black, 0.

Each function accepts torch tensors or numpy arrays and returns a Python float (computed in
float64).
"""

from __future__ import annotations

import math

import numpy as np

from roomlight.core.color import DISPLAY_GAMMA, to_display
from roomlight.errors import RoomlightError, ShapeError

__all__ = ["METRICS", "HIGHER_IS_BETTER", "LDR_GAMMA", "to_ldr", "psnr_ldr", "rmse_hdr", "angular_error_deg",
           "score_view"]

#: Metric names in the order of the paper's Table 2.
METRICS = ("psnr_ldr", "rmse_hdr", "angular_error")
#: Direction of each metric (for highlighting the best method in reports).
HIGHER_IS_BETTER = {"psnr_ldr": True, "rmse_hdr": False, "angular_error": False}
#: The display gamma of the LDR metric and of the benchmark's 8-bit recordings.
LDR_GAMMA = DISPLAY_GAMMA
#: RGB vectors shorter than this count as black in the angular error.
BLACK = 1e-12


def _arrays(pred, target, mask) -> tuple[np.ndarray, np.ndarray]:
    """(P, 3) float64 pixels of pred and target selected by the mask."""
    p = _np(pred)
    t = _np(target)
    if p.ndim != 3 or p.shape[-1] != 3 or p.shape != t.shape:
        raise ShapeError(f"metrics: expected two (H, W, 3) images of the same shape, got {p.shape} and {t.shape}")
    if mask is None:
        m = np.ones(p.shape[:2], bool)
    else:
        m = _np(mask).astype(bool)
        if m.shape != p.shape[:2]:
            raise ShapeError(f"metrics: mask is {m.shape}, images are {p.shape[:2]}")
    if not m.any():
        raise RoomlightError("metrics: the mask selects no pixel")
    return p[m], t[m]


def _np(x) -> np.ndarray:
    if hasattr(x, "detach"):
        x = x.detach().cpu().numpy()
    return np.asarray(x, dtype=np.float64)


#: The benchmark's LDR mapping under its old name: no exposure (the recordings are already
#: exposed), only clip and gamma; see :func:`roomlight.core.color.to_display`.
to_ldr = to_display


def psnr_ldr(pred, target, mask=None) -> float:
    """PSNR (dB) after gamma 2.2 and clipping to [0, 1], over mask pixels; inf when identical.

    Args:
        pred, target: (H, W, 3) linear radiance.
        mask: (H, W) bool (nonzero = scored), or None for all pixels.
    """
    p, t = _arrays(pred, target, mask)
    mse = float(np.mean((to_display(p) - to_display(t)) ** 2))
    return math.inf if mse == 0.0 else 10.0 * math.log10(1.0 / mse)


def rmse_hdr(pred, target, mask=None) -> float:
    """Root-mean-square error of linear radiance over mask pixels and channels (radiance units)."""
    p, t = _arrays(pred, target, mask)
    return float(np.sqrt(np.mean((p - t) ** 2)))


def angular_error_deg(pred, target, mask=None) -> float:
    """Mean per-pixel angle (degrees) between predicted and target RGB vectors over mask pixels.

    Computed as ``atan2(|p x t|, p . t)``, accurate for small angles.
    """
    p, t = _arrays(pred, target, mask)
    cross = np.linalg.norm(np.cross(p, t), axis=-1)
    dot = np.sum(p * t, axis=-1)
    ang = np.degrees(np.arctan2(cross, dot))
    np_black = np.linalg.norm(p, axis=-1) < BLACK
    nt_black = np.linalg.norm(t, axis=-1) < BLACK
    ang = np.where(np_black ^ nt_black, 90.0, ang)
    ang = np.where(np_black & nt_black, 0.0, ang)
    return float(np.mean(ang))


def score_view(pred, target, mask) -> dict[str, float]:
    """All metrics of :data:`METRICS` for one view, plus the number of scored pixels."""
    m = _np(mask).astype(bool)
    return {"psnr_ldr": psnr_ldr(pred, target, m), "rmse_hdr": rmse_hdr(pred, target, m),
            "angular_error": angular_error_deg(pred, target, m), "pixels": int(m.sum())}
