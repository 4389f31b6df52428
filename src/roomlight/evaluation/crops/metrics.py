"""The three-sphere protocol's numbers, as the light-estimation field computes them.

StyleLight, EverLight, DiffusionLight and LuxDiT score a predicted panorama by rendering three spheres
(diffuse, matte silver, mirror) under it and under the true panorama and comparing the two renders. To
place roomlight among them its scores must be computed the same way, including the choices that are
not the obvious ones:

- **Tone mapping** (:func:`tonemap`): E' = alpha E^(1/gamma), alpha = m / (the p-th percentile of the
  *non-zero* values of E^(1/gamma), every channel of every pixel pooled, + 1e-10), optionally clipped to
  [0, 1]. The input crop is made from the panorama tone-mapped with gamma 2.4, p = 99, m = 0.9,
  clipped; the panoramas the spheres are rendered under are normalised with gamma 2.4, p = 50 (the
  median), m = 0.5, not clipped (:data:`CROP_TONEMAP`, :data:`SCORE_TONEMAP`).
- **Sums over the sphere's pixels, divided by the pixel count, not by the values' count**: with three
  channels, the squared errors of a pixel add up before the division.
  RMSE = sqrt(sum_mask sum_c (p - g)^2 / N).
- **Scale-invariant RMSE**: the same after one least-squares scale s of the prediction over every masked
  value of every channel: min_s sum (s p - g)^2 = c - b^2 / (4 a), with a = sum p^2, b = -2 sum p g,
  c = sum g^2.
- **Angular error**: per pixel, the angle between the two RGB vectors (cosine clipped to [0, 1]; a pixel
  where either vector is zero counts 0 degrees), summed over the mask and divided by N, in degrees.
- **Normalised RMSE**: each render rescaled by its own 0.01st and 99.9th percentiles over *all* its
  values (x - p_0.01) / (p_99.9 - p_0.01), then the RMSE over the mask.

Images are (H, W, 3) float arrays; ``mask`` is (H, W) bool (the rendered sphere's pixels).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from roomlight.errors import ShapeError

__all__ = ["Tonemap", "CROP_TONEMAP", "SCORE_TONEMAP", "tonemap", "sphere_rmse", "sphere_si_rmse",
           "sphere_angular_error", "normalise_percentiles", "sphere_normalised_rmse", "sphere_scores"]


@dataclass(frozen=True)
class Tonemap:
    """E' = alpha E^(1/gamma), alpha = mapping / (the percentile of the non-zero values + 1e-10)."""

    gamma: float
    percentile: float
    mapping: float
    clip: bool


#: The input crop: the panorama's 99th percentile at 0.9, clipped (an 8-bit-like photograph).
CROP_TONEMAP = Tonemap(gamma=2.4, percentile=99.0, mapping=0.9, clip=True)
#: The panoramas the spheres are scored under: the median at 0.5, HDR kept.
SCORE_TONEMAP = Tonemap(gamma=2.4, percentile=50.0, mapping=0.5, clip=False)


def tonemap(image: np.ndarray, t: Tonemap) -> tuple[np.ndarray, float]:
    """(the tone-mapped image float32, alpha) of a linear HDR image (see the module docstring)."""
    x = np.power(np.clip(np.asarray(image, np.float64), 0.0, None), 1.0 / t.gamma)
    nonzero = x[x > 0]
    level = np.percentile(nonzero if nonzero.size else x, t.percentile)
    alpha = t.mapping / (float(level) + 1e-10)
    out = alpha * x
    if t.clip:
        out = np.clip(out, 0.0, 1.0)
    return out.astype(np.float32), alpha


def _check(pred, gt, mask) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    p, g = np.asarray(pred, np.float64)[..., :3], np.asarray(gt, np.float64)[..., :3]
    m = np.asarray(mask, bool)
    if p.shape != g.shape or p.shape[:2] != m.shape or p.shape[-1] != 3:
        raise ShapeError(f"sphere scores: prediction {p.shape}, truth {g.shape} and mask {m.shape} must be "
                         "(H, W, 3), (H, W, 3) and (H, W)")
    n = float(m.sum())
    if n == 0:
        raise ShapeError("sphere scores: the mask covers no pixel")
    return p, g, m, n


def sphere_rmse(pred, gt, mask) -> float:
    """sqrt(sum over the mask's pixels and the channels of (pred - gt)^2 / pixels)."""
    p, g, m, n = _check(pred, gt, mask)
    return float(np.sqrt(((p - g) ** 2)[m].sum() / n))


def sphere_si_rmse(pred, gt, mask) -> float:
    """The RMSE after the one scale of ``pred`` (over every masked value) that fits ``gt`` best."""
    p, g, m, n = _check(pred, gt, mask)
    a = float((p[m] ** 2).sum())
    b = float(-2.0 * (p[m] * g[m]).sum())
    c = float((g[m] ** 2).sum())
    if a == 0.0:  # a black prediction: no scale changes it
        return float(np.sqrt(c / n))
    return float(np.sqrt(max(c - b * b / (4.0 * a), 0.0) / n))


def sphere_angular_error(pred, gt, mask) -> float:
    """Mean over the mask's pixels of the angle (degrees) between the RGB vectors; a pixel where either is
    zero counts 0."""
    p, g, m, n = _check(pred, gt, mask)
    norms = np.linalg.norm(p, axis=-1) * np.linalg.norm(g, axis=-1)
    dot = (p * g).sum(-1)
    cos = np.divide(dot, norms, out=np.full(dot.shape, np.nan), where=norms > 0)
    angle = np.nan_to_num(np.arccos(np.clip(cos, 0.0, 1.0)), nan=0.0)
    return float(np.degrees(angle[m].sum() / n))


def normalise_percentiles(image: np.ndarray) -> np.ndarray:
    """(x - p_0.01) / (p_99.9 - p_0.01), the percentiles over every value of the image."""
    x = np.asarray(image, np.float64)
    lo, hi = np.percentile(x, 0.01), np.percentile(x, 99.9)
    return (x - lo) / (hi - lo)


def sphere_normalised_rmse(pred, gt, mask) -> float:
    """The RMSE of the two renders each rescaled by its own percentiles (:func:`normalise_percentiles`)."""
    p, g, m, _ = _check(pred, gt, mask)
    return sphere_rmse(normalise_percentiles(p), normalise_percentiles(g), m)


def sphere_scores(pred, gt, mask) -> dict[str, float]:
    """``rmse``, ``si_rmse``, ``angular_error`` (degrees) and ``norm_rmse`` of one sphere's two renders."""
    return {"rmse": sphere_rmse(pred, gt, mask), "si_rmse": sphere_si_rmse(pred, gt, mask),
            "angular_error": sphere_angular_error(pred, gt, mask),
            "norm_rmse": sphere_normalised_rmse(pred, gt, mask)}
