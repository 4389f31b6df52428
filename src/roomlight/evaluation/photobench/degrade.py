"""Degraded depth: what the methods get when geometry comes from an estimator, not from the renderer.

Monocular depth estimators err mostly in scale and in smooth, low-frequency distortions, not in
per-pixel noise (which a fit averages away). The degraded depth is therefore

    depth' = scale * depth * exp(sigma * n),

``n`` a smooth random field of unit RMS: independent standard normal values on a coarse grid (one
node per ``cell`` pixels), bilinearly interpolated to the image and divided by its RMS. The
factor exp(sigma n) keeps depth positive; for small sigma it is 1 + sigma n, a relative error of
RMS sigma. The ground truth (``truth/depth.exr``) always keeps the exact depth.
"""

from __future__ import annotations

import numpy as np

__all__ = ["NOISE_CELL", "smooth_field", "degrade_depth"]

#: Pixels between two nodes of the noise grid.
NOISE_CELL = 16


def smooth_field(height: int, width: int, rng: np.random.Generator, cell: int = NOISE_CELL) -> np.ndarray:
    """(H, W) float64 smooth random field with RMS exactly 1 (see the module docstring)."""
    gh, gw = height // cell + 2, width // cell + 2
    grid = rng.standard_normal((gh, gw))
    y = (np.arange(height) + 0.5) / cell
    x = (np.arange(width) + 0.5) / cell
    y0, x0 = np.floor(y).astype(int), np.floor(x).astype(int)
    fy, fx = (y - y0)[:, None], (x - x0)[None, :]
    g = lambda a, b: grid[np.ix_(a, b)]  # noqa: E731
    field = ((1 - fy) * (1 - fx) * g(y0, x0) + (1 - fy) * fx * g(y0, x0 + 1)
             + fy * (1 - fx) * g(y0 + 1, x0) + fy * fx * g(y0 + 1, x0 + 1))
    return field / np.sqrt(np.mean(field ** 2))


def degrade_depth(depth: np.ndarray, noise: float = 0.0, scale: float = 1.0,
                  rng: np.random.Generator | None = None) -> np.ndarray:
    """The depth a method gets: ``scale * depth * exp(noise * field)``; (H, W) float32 metres.

    ``rng`` seeds the field (needed when ``noise > 0``). With ``noise = 0`` and ``scale = 1`` the
    depth comes back unchanged.
    """
    d = np.asarray(depth, np.float64)
    out = d * float(scale)
    if noise > 0:
        if rng is None:
            raise ValueError("degrade_depth: noise needs a random generator")
        out = out * np.exp(float(noise) * smooth_field(d.shape[0], d.shape[1], rng))
    return out.astype(np.float32)
