"""Fusing per-view depth into one panorama: a global consistency solve on the views' overlaps.

Each view k's prediction q_k is pasted onto the panorama grid (bilinear, inverse gnomonic) with
a blending weight that falls smoothly to zero at the view's border,
w_k = ((1 - x^2)(1 - y^2))^2 in the view's normalised image coordinates. The radial depth view k
claims at pixel p is

    r_k(p) = (s_k q_k(p) + t_k) g_k(p)

with g_k = 1 / cos(angle to the axis) for planar depth and 1 for ray distance. The unknowns
are solved on the overlaps, every pair of views weighted by the pixels' solid angle and both
views' blending weights, with Huber-weighted (IRLS) residuals so depth edges that the two
views resample differently do not pull the solution:

- **scale** (every kind): a_k = log s_k by least squares on log r_k - log r_l, with the gauge
  sum a_k = 0 (for a metric estimator that keeps the views' average metric scale);
- **affine**: then (s_k, t_k) jointly, linear least squares on (r_k - r_l) / r_ref with r_ref
  the current fused depth, the gauge sum s_k fixed and a weak ridge on the shifts.

**Pole constraints.** In the equirectangular grid the poles are a single point each, but with
solid-angle weights their neighbourhood counts for almost nothing in the solve, so the views
meeting there could disagree. Pixels within ``pole_deg`` of each pole are up-weighted until the
two caps carry ``pole_share`` of the overlap weight: the views that see a pole agree at it.

The fused log-depth is the blending-weighted mean of the aligned views' log-depths; every
weight is a continuous function on the sphere, so the result is continuous across the seam
column and at both poles. Pixels no view judged valid are filled by diffusion from their
neighbours (with the spherical padding's neighbours across the seam and the poles).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import torch

from roomlight.errors import RoomlightError
from roomlight.core.geometry.equirect import pixel_directions, pixel_solid_angles
from roomlight.core.geometry.padding import spherical_pad
from roomlight.datagen.prepare.views import View, view_plane_coordinates, view_to_panorama

__all__ = ["FusionResult", "fuse_views", "floor_distance", "blend_weight"]


def blend_weight(height: int, width: int) -> np.ndarray:
    """(h, w) view blending weight ((1 - x^2)(1 - y^2))^2: 1 at the centre, 0 at the border."""
    x, y = view_plane_coordinates(height, width)
    return ((1.0 - x * x) * (1.0 - y * y)) ** 2


@dataclass
class FusionResult:
    """The fused panorama depth and what the solve found.

    Attributes:
        depth: (H, W) float64 radial depth in the estimator's units after alignment (metres
            for a metric estimator; an arbitrary common scale otherwise).
        scales, shifts: per-view s_k, t_k (t_k = 0 unless affine).
        overlap_before, overlap_after: solid-angle weighted median |log r_k - log r_l| over all
            overlapping pairs, before and after alignment.
        filled: pixels no view covered validly (filled by diffusion).
    """

    depth: np.ndarray
    scales: list = field(default_factory=list)
    shifts: list = field(default_factory=list)
    overlap_before: float = float("nan")
    overlap_after: float = float("nan")
    filled: int = 0

    def summary(self) -> dict:
        return {"scales": [round(s, 6) for s in self.scales], "shifts": [round(t, 6) for t in self.shifts],
                "overlap_log_residual_before": round(self.overlap_before, 6),
                "overlap_log_residual_after": round(self.overlap_after, 6), "filled_pixels": self.filled}


def _weighted_median(x: np.ndarray, w: np.ndarray) -> float:
    if x.size == 0 or w.sum() <= 0:
        return float("nan")
    o = np.argsort(x)
    c = np.cumsum(w[o])
    return float(x[o][np.searchsorted(c, 0.5 * c[-1])])


def _huber(e: np.ndarray, delta: float) -> np.ndarray:
    a = np.abs(e)
    return np.where(a <= delta, 1.0, delta / np.maximum(a, 1e-300))


def _fill(logd: np.ndarray, known: np.ndarray) -> np.ndarray:
    """Fill unknown pixels by repeated averaging of known 4-neighbours on the sphere."""
    x = np.where(known, logd, 0.0)
    k = known.astype(np.float64)
    h = x.shape[0]
    for _ in range(4 * h):
        if k.min() > 0:
            break
        t = torch.from_numpy(np.stack([x * k, k]))[None]
        p = spherical_pad(t, 1)[0].numpy()
        s = p[:, :-2, 1:-1] + p[:, 2:, 1:-1] + p[:, 1:-1, :-2] + p[:, 1:-1, 2:]
        grow = (k == 0) & (s[1] > 0)
        x = np.where(grow, s[0] / np.maximum(s[1], 1e-300), x)
        k = np.where(grow, 1.0, k)
    return x


def fuse_views(views: list[View], depths: list[np.ndarray], valids: list[np.ndarray], height: int, *,
               kind: str = "scale", depth_type: str = "z", pole_deg: float = 10.0, pole_share: float = 0.2,
               huber: float = 0.05, iterations: int = 5) -> FusionResult:
    """Align and blend per-view depth into an (height, 2 height) radial depth panorama.

    Args:
        views: the views (:func:`roomlight.datagen.prepare.views.cut_views`).
        depths, valids: per view (h, w) positive predictions and bool validity
            (:func:`roomlight.datagen.prepare.estimators.run_estimator`).
        height: panorama height H (width 2H).
        kind: ``metric``, ``scale`` or ``affine`` (what the numbers mean, see the module docstring).
        depth_type: ``z`` (planar) or ``distance`` (along the ray).
        pole_deg, pole_share: the pole constraints (module docstring).
        huber: IRLS threshold on the relative residual.
        iterations: IRLS iterations per stage.
    """
    if kind not in ("metric", "scale", "affine"):
        raise RoomlightError(f"fuse_views: unknown estimator kind {kind!r}")
    K = len(views)
    H, W = height, 2 * height
    q = np.zeros((K, H, W))
    g = np.ones((K, H, W))
    wt = np.zeros((K, H, W))
    for k, (v, d, ok) in enumerate(zip(views, depths, valids)):
        bw = blend_weight(*v.size)
        inv_cos = 1.0 / v.cos_to_axis() if depth_type == "z" else np.ones(v.size)
        med = float(np.median(d[ok])) if ok.any() else 1.0
        stack = np.stack([np.where(ok, d, med), inv_cos, bw, ok.astype(np.float64)], axis=-1)
        pasted, inside = view_to_panorama(stack, v, H)
        good = inside & (pasted[..., 3] > 0.999) & (pasted[..., 0] > 0)  # all four bilinear taps valid
        q[k], g[k] = pasted[..., 0], pasted[..., 1]
        wt[k] = np.where(good, pasted[..., 2], 0.0)
    if not (wt > 0).any(axis=0).any():
        raise RoomlightError("no view returned a valid depth")

    # pixel weights: solid angle, with the pole caps raised to carry pole_share of the total
    omega = pixel_solid_angles(H, W, dtype=torch.float64).numpy()
    theta = (np.arange(H) + 0.5) * math.pi / H
    polar = (theta < math.radians(pole_deg)) | (theta > math.pi - math.radians(pole_deg))
    cap_w, rest_w = omega[polar].sum(), omega[~polar].sum()
    if cap_w > 0 and 0 < pole_share < 1:
        omega = omega.copy()
        omega[polar] *= pole_share / (1 - pole_share) * rest_w / cap_w

    pairs = []
    for k in range(K):
        for m in range(k + 1, K):
            both = (wt[k] > 0) & (wt[m] > 0)
            if both.any():
                pairs.append((k, m, both, omega[both] * wt[k][both] * wt[m][both]))
    logr = np.log(np.maximum(q * g, 1e-300))

    def overlap_residual(lr):
        es = np.concatenate([lr[k][b] - lr[m][b] for k, m, b, _ in pairs])
        ws = np.concatenate([w for *_, w in pairs])
        return _weighted_median(np.abs(es), ws)

    before = overlap_residual(logr)
    # --- stage 1: log-scales
    a = np.zeros(K)
    for _ in range(iterations):
        N = np.zeros((K, K))
        rhs = np.zeros(K)
        for k, m, b, w in pairs:
            d = logr[k][b] - logr[m][b]
            ww = w * _huber(a[k] - a[m] + d, huber)
            sw, swd = ww.sum(), (ww * d).sum()
            N[k, k] += sw
            N[m, m] += sw
            N[k, m] -= sw
            N[m, k] -= sw
            rhs[k] -= swd
            rhs[m] += swd
        gauge = N.trace() / K
        a = np.linalg.solve(N + gauge * np.ones((K, K)) / K, rhs)  # adds (sum a)^2 to the objective
    s = np.exp(a)
    t = np.zeros(K)

    def fused(s, t):
        r = (s[:, None, None] * q + t[:, None, None]) * g
        ok = (wt > 0) & (r > 0)
        lr = np.log(np.where(ok, r, 1.0))
        ww = np.where(ok, wt, 0.0)
        tot = ww.sum(axis=0)
        out = (ww * lr).sum(axis=0) / np.maximum(tot, 1e-300)
        return out, tot > 0, lr

    # --- stage 2: scale and shift
    if kind == "affine":
        s_sum = s.sum()
        for _ in range(iterations):
            ref, _, _ = fused(s, t)
            rref = np.exp(ref)
            scale_ref = float(np.median(rref))
            N = np.zeros((2 * K, 2 * K))
            for k, m, b, w in pairs:
                # residual e = [s_k q_k g_k + t_k g_k - s_m q_m g_m - t_m g_m] / r_ref, linear in (s, t)
                cols = np.stack([q[k][b] * g[k][b], g[k][b], -q[m][b] * g[m][b], -g[m][b]]) / rref[b]
                e = cols[0] * s[k] + cols[1] * t[k] + cols[2] * s[m] + cols[3] * t[m]
                ww = w * _huber(e, huber)
                idx = [k, K + k, m, K + m]
                N[np.ix_(idx, idx)] += (cols * ww) @ cols.T
            # a weak ridge keeps the shifts (weakly constrained: they only show through the
            # change of obliquity across an overlap) near 0, in units of the typical depth
            total = sum(w.sum() for *_, w in pairs)
            A = N + np.diag(np.r_[np.zeros(K), np.full(K, 1e-3 * total / scale_ref**2)])
            # gauge: sum s = s_sum, as a heavily weighted equation
            c = np.r_[np.ones(K), np.zeros(K)]
            big = 1e3 * np.trace(N[:K, :K]) / K
            A = A + big * np.outer(c, c)
            rhs = big * c * s_sum
            sol = np.linalg.solve(A, rhs)
            s, t = sol[:K], sol[K:]
            if (s <= 0).any():
                raise RoomlightError("the affine alignment gave a non-positive view scale: the views disagree too much")
    logd, known, lr = fused(s, t)
    after = overlap_residual(lr)
    filled = int((~known).sum())
    if filled:
        logd = _fill(logd, known)
    return FusionResult(np.exp(logd), [float(v) for v in s], [float(v) for v in t], before, after, filled)


def floor_distance(depth: np.ndarray, within_deg: float = 50.0, top: float = 0.9) -> float:
    """The camera's height above the floor, from a radial depth panorama (same units as ``depth``).

    Below the camera every surface but the floor is above the floor, so among the pixels within
    ``within_deg`` of the nadir the floor is the largest vertical drop d = -r cos(theta).
    Returns the solid-angle weighted median of d over the pixels whose drop is at least ``top``
    times the 98th percentile (the floor, robust to noise and to a few outliers).

    Args:
        depth: (H, W) radial depth.
    """
    d = np.asarray(depth, np.float64)
    H, W = d.shape
    dirs = pixel_directions(H, W, dtype=torch.float64).numpy()
    omega = pixel_solid_angles(H, W, dtype=torch.float64).numpy()
    theta = (np.arange(H) + 0.5) * math.pi / H
    rows = theta > math.pi - math.radians(within_deg)
    drop = (-d * dirs[..., 1])[rows].ravel()
    w = omega[rows].ravel()
    if drop.size == 0:
        raise RoomlightError("floor_distance: the panorama is too small to see the floor")
    o = np.argsort(drop)
    c = np.cumsum(w[o])
    q98 = drop[o][np.searchsorted(c, 0.98 * c[-1])]
    sel = drop >= top * q98
    return _weighted_median(drop[sel], w[sel])
