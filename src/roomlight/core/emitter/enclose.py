"""Keeping a scene inside a 2.5D area light.

A 2.5D light is star-shaped about its centre: in every direction it has one surface, at its radial
depth. A scene placed in it (a photograph's depth mesh, the objects a user inserts) must lie *inside*
that surface, or the renderer sees nonsense:

- a surface point beyond the light's surface is outside the room: every ray it sends into the room
  meets the emissive mesh from behind, which emits nothing, so it is lit by nothing;
- a surface point exactly on it (a photograph's wall under a light fitted to that wall) is both the
  emitter and a receiver at one place, and which of the two a ray meets is decided by rounding.

Both happen: the room's own panorama seen from another point (the benchmark's reference light, any
panorama captured away from the camera) hides, behind every piece of furniture, floor that the
photograph shows; and a light fitted to a photograph passes through the walls it shows. The remedy is
to push the light's surface out, in each direction, to just beyond the farthest scene point there:
the scene's visible surfaces then *receive* the light and reflect it (with the albedo the photograph
gives them), as they do in the room, and the emitter's radiance in those directions lights the scene
from behind them, where nothing but the scene itself can see it.
"""

from __future__ import annotations

import numpy as np

__all__ = ["enclosing_depth", "ENCLOSE_MARGIN"]

#: The light's surface is pushed to this fraction beyond the farthest scene point in its direction.
ENCLOSE_MARGIN = 0.03


def enclosing_depth(depth: np.ndarray, points: np.ndarray, margin: float = ENCLOSE_MARGIN,
                    dilate: int = 1) -> tuple[np.ndarray, float]:
    """The light's radial depth pushed out so that every point lies inside it.

    Args:
        depth: (H, W) the light's radial depth (metres), W = 2 H.
        points: (N, 3) scene points in the light's frame (its centre at the origin), metres; the
            vertices of a mesh (with ``dilate`` covering the triangles between them).
        margin: how far beyond the farthest point, as a fraction of its distance.
        dilate: texels of neighbourhood over which each point's distance is spread (a triangle spans
            the texels between its vertices; 1 covers meshes as fine as the panorama).
    Returns:
        ((H, W) float32 depth, the share of texels that moved).
    """
    d = np.asarray(depth, dtype=np.float64)
    h, w = d.shape
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    r = np.linalg.norm(p, axis=1)
    ok = np.isfinite(r) & (r > 1e-9)
    p, r = p[ok], r[ok]
    need = np.zeros((h, w))
    if len(p):
        # Texel of each point, in the panorama convention of roomlight.core.geometry.equirect:
        # u = atan2(x, -z) / 2 pi, v = atan2(sqrt(x^2 + z^2), y) / pi.
        u = np.remainder(np.arctan2(p[:, 0], -p[:, 2]) / (2 * np.pi), 1.0)
        v = np.arctan2(np.hypot(p[:, 0], p[:, 2]), p[:, 1]) / np.pi
        col = np.minimum((u * w).astype(np.int64), w - 1)
        row = np.minimum((v * h).astype(np.int64), h - 1)
        np.maximum.at(need, (row, col), r * (1.0 + margin))
        if dilate > 0:
            grown = need.copy()
            for dy in range(-dilate, dilate + 1):
                for dx in range(-dilate, dilate + 1):
                    shifted = np.roll(need, dx, axis=1)  # columns wrap around the panorama
                    if dy > 0:
                        shifted = np.concatenate([shifted[:1].repeat(dy, 0), shifted[:-dy]], 0)
                    elif dy < 0:
                        shifted = np.concatenate([shifted[-dy:], shifted[-1:].repeat(-dy, 0)], 0)
                    grown = np.maximum(grown, shifted)
            need = grown
    out = np.maximum(d, need)
    return out.astype(np.float32), float((out > d).mean())
