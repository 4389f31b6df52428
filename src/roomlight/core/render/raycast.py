"""Casting rays against a Mitsuba scene from numpy: first hits, shape coverage of a camera's pixels, and
high sample counts rendered in averaged passes. Every benchmark and study casts and splits through here.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from roomlight.errors import RoomlightError
from roomlight.core.render.variant import mitsuba

__all__ = ["RayCaster", "sphere_directions", "shape_coverage", "render_in_passes", "MAX_RAYS_PER_CAST", "MAX_SAMPLES_PER_PASS"]

#: Rays per cast of :func:`shape_coverage` (bounds memory: ~100 bytes of state per ray).
MAX_RAYS_PER_CAST = 1 << 22
#: Paths per Mitsuba launch (pixels x spp) in :func:`render_in_passes`.
MAX_SAMPLES_PER_PASS = 1 << 24


def sphere_directions(n: int = 26) -> np.ndarray:
    """(n, 3) unit vectors spread evenly over the sphere (a Fibonacci lattice)."""
    k = np.arange(n) + 0.5
    y = 1.0 - 2.0 * k / n
    r = np.sqrt(np.clip(1.0 - y * y, 0.0, None))
    phi = math.pi * (3.0 - math.sqrt(5.0)) * k
    return np.stack([r * np.cos(phi), y, r * np.sin(phi)], -1)


class RayCaster:
    """Batched ray casts against a Mitsuba scene (numpy in, numpy out)."""

    def __init__(self, scene):
        self.scene = scene
        self.mi = mitsuba()

    def cast(self, origins, directions) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """First hits of the rays ``origins + t directions``.

        Args:
            origins: (N, 3) or (3,) metres; directions: (N, 3), normalised here. A zero direction (a
                point cast at itself) is a miss, as a NaN ray would be.
        Returns:
            t: (N,) metres along the unit direction, inf for a miss; normals: (N, 3) geometric normals;
            points: (N, 3) hit points (the origin for a miss).
        """
        mi = self.mi
        d = np.asarray(directions, np.float64).reshape(-1, 3)
        o = np.broadcast_to(np.asarray(origins, np.float64).reshape(-1, 3), d.shape)
        length = np.linalg.norm(d, axis=-1, keepdims=True)
        zero = length[:, 0] == 0
        d = d / np.where(zero[:, None], 1.0, length)
        ray = mi.Ray3f(mi.Point3f(*[mi.Float(o[:, k].astype(np.float32)) for k in range(3)]),
                       mi.Vector3f(*[mi.Float(d[:, k].astype(np.float32)) for k in range(3)]))
        si = self.scene.ray_intersect(ray)
        valid = np.asarray(si.is_valid(), bool) & ~zero
        t = np.where(valid, np.asarray(si.t, np.float64), np.inf)
        n = np.stack([np.asarray(si.n[k], np.float64) for k in range(3)], -1)
        return t, n, o + np.where(valid[:, None], t[:, None], 0.0) * d

    def distances(self, origins, directions) -> np.ndarray:
        """(N,) metres to the first surface along each ray; inf where a ray escapes."""
        return self.cast(origins, directions)[0]


def shape_coverage(scene, rays: Callable, shapes: list, width: int, height: int, supersample: int = 4,
                   max_rays: int | None = None) -> np.ndarray:
    """Per-pixel coverage of each of ``shapes`` (Mitsuba shape objects of ``scene``) seen by a camera.

    Each pixel sends ``supersample``² rays through stratified sub-pixel centres; a ray counts for shape k
    when its first hit in ``scene`` is k (so occluders in ``scene`` hide it).

    Args:
        rays: ``rays(x, y)`` -> ``mi.Ray3f`` through sub-pixel centres given in sub-pixel units: (N,) float64
            ``x`` in [0, width·s), ``y`` in [0, height·s) (row 0 at the top); the camera's own convention
            (pixels, or the film's [0, 1] coordinates) is the caller's to apply.
    Returns:
        (K, height, width) float32: the share of a pixel's rays whose first hit is shape k.
    """
    import drjit as dr

    mi = mitsuba()
    s, w, h = int(supersample), int(width), int(height)
    out = np.zeros((len(shapes), h, w), np.float32)
    xs = np.arange(w * s) + 0.5
    rows = max(1, min(h, (max_rays or MAX_RAYS_PER_CAST) // (w * s * s)))  # image rows per cast
    for r0 in range(0, h, rows):
        r1 = min(h, r0 + rows)
        jj, ii = np.meshgrid(xs, np.arange(r0 * s, r1 * s) + 0.5)
        si = scene.ray_intersect(rays(jj.ravel(), ii.ravel()))
        for k, shape in enumerate(shapes):
            hit = np.asarray(dr.select(si.is_valid() & (si.shape == mi.ShapePtr(shape)), 1.0, 0.0), np.float32)
            out[k, r0:r1] = hit.reshape(r1 - r0, s, w, s).mean(axis=(1, 3))
    return out


def render_in_passes(render: Callable, spp: int, pixels: int, seed: int = 0,
                     max_samples: int = MAX_SAMPLES_PER_PASS):
    """``render(n, seed)`` (an (h, w, C) float64 array or tensor estimating the image from ``n`` samples per
    pixel) repeated in passes of at most ``max_samples`` paths and averaged.

    One Mitsuba wavefront of 1000 x 1000 pixels at 4096 spp (the paper's setting) would hold ~4e9 paths
    at once. Pass ``k`` uses seed ``seed + k``; the passes split ``spp`` as evenly as possible and are
    weighted by their sample counts, so the result estimates the same image as one launch.

    Returns:
        the float64 average, of the type ``render`` returns.
    """
    if spp <= 0:
        raise RoomlightError(f"render: spp must be positive, got {spp}")
    passes = min(spp, max(1, math.ceil(spp * int(pixels) / max_samples)))
    base, extra = divmod(spp, passes)
    acc = None
    for k in range(passes):
        n = base + (1 if k < extra else 0)
        img = render(n, int(seed) + k) * n
        acc = img if acc is None else acc + img
    return acc / spp
