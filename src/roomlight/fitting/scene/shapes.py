"""Built-in object shapes: varied, non-convex meshes that stand in for scanned models.

The paper fits illumination to the Stanford bunny and armadillo, which roomlight does not ship.
These procedural meshes play their role: each is closed, outward-facing, centred at the origin
and scaled to a bounding radius of 1 (so a scene places it with a translation and one scale).
Any OBJ/PLY file works the same way through the scene description.

Shapes: ``knot`` (a trefoil tube), ``blob`` (a bumpy, dented sphere), ``torus``, ``sphere``
(the probe), ``cup`` (a thick open cylinder with a floor), ``spiky`` (a star-like body).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from roomlight.errors import RoomlightError

__all__ = ["BUILTIN_SHAPES", "builtin_shape"]


def _grid_faces(rows: int, cols: int, wrap_rows: bool, wrap_cols: bool) -> np.ndarray:
    """Triangles of a rows x cols vertex grid (index r * cols + c), optionally wrapping."""
    faces = []
    rr = rows if wrap_rows else rows - 1
    cc = cols if wrap_cols else cols - 1
    for r in range(rr):
        for c in range(cc):
            a = r * cols + c
            b = r * cols + (c + 1) % cols
            d = ((r + 1) % rows) * cols + c
            e = ((r + 1) % rows) * cols + (c + 1) % cols
            faces += [(a, d, b), (b, d, e)]
    return np.asarray(faces, dtype=np.int64)


def _tube(curve: np.ndarray, radius: float, sides: int = 16) -> tuple[np.ndarray, np.ndarray]:
    """A closed tube of ``radius`` around a closed polyline ``curve`` (N, 3)."""
    n = len(curve)
    tangent = np.roll(curve, -1, 0) - np.roll(curve, 1, 0)
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    # parallel-transported frame (avoids twisting of a Frenet frame)
    normal = np.cross(tangent[0], [0.0, 0.0, 1.0] if abs(tangent[0, 2]) < 0.9 else [1.0, 0.0, 0.0])
    normal /= np.linalg.norm(normal)
    normals = [normal]
    for i in range(1, n):
        v = normals[-1] - tangent[i] * np.dot(normals[-1], tangent[i])
        normals.append(v / np.linalg.norm(v))
    normals = np.array(normals)
    binormals = np.cross(tangent, normals)
    ang = 2 * np.pi * np.arange(sides) / sides
    ring = np.cos(ang)[None, :, None] * normals[:, None] + np.sin(ang)[None, :, None] * binormals[:, None]
    verts = (curve[:, None] + radius * ring).reshape(-1, 3)
    return verts, _grid_faces(n, sides, True, True)


def _uv_sphere(rows: int = 24, cols: int = 48):
    theta = np.linspace(0, np.pi, rows + 1)[1:-1]
    phi = 2 * np.pi * np.arange(cols) / cols
    st, ct = np.sin(theta)[:, None], np.cos(theta)[:, None]
    verts = np.stack([st * np.cos(phi), ct * np.ones_like(phi), st * np.sin(phi)], -1).reshape(-1, 3)
    faces = list(map(tuple, _grid_faces(rows - 1, cols, False, True)))
    top, bottom = len(verts), len(verts) + 1
    last = (rows - 2) * cols
    for c in range(cols):
        faces.append((top, c, (c + 1) % cols))
        faces.append((bottom, last + (c + 1) % cols, last + c))
    verts = np.concatenate([verts, [[0, 1, 0], [0, -1, 0]]])
    return verts, np.asarray(faces, dtype=np.int64)


def _knot():
    t = np.linspace(0, 2 * np.pi, 240, endpoint=False)
    curve = np.stack([np.sin(t) + 2 * np.sin(2 * t), np.cos(t) - 2 * np.cos(2 * t), -np.sin(3 * t)], -1)
    return _tube(curve, 0.55, 18)


def _torus():
    t = np.linspace(0, 2 * np.pi, 96, endpoint=False)
    curve = np.stack([np.cos(t), np.zeros_like(t), np.sin(t)], -1)
    return _tube(curve, 0.38, 24)


def _blob():
    v, f = _uv_sphere(40, 80)
    x, y, z = v.T
    r = 1 + 0.22 * np.sin(3 * x + 1) * np.cos(2 * y) + 0.18 * np.sin(4 * z + 2 * y) - 0.3 * np.exp(-8 * ((x - 0.6) ** 2 + (y - 0.4) ** 2))
    return v * r[:, None], f


def _spiky():
    v, f = _uv_sphere(48, 96)
    x, y, z = v.T
    r = 0.75 + 0.35 * np.clip(np.cos(5 * np.arctan2(z, x)) * np.sin(np.pi * (y + 1) / 2) ** 2, 0, None) + 0.12 * y
    return v * r[:, None], f


def _cup():
    # A profile (radius, height) revolved around y: outer wall, rim, inner wall, inner floor, base.
    prof = [(0.0, -1.0), (0.8, -1.0), (0.9, -0.9), (0.95, 0.9), (0.85, 1.0), (0.75, 0.9), (0.7, -0.7), (0.0, -0.7)]
    cols = 64
    phi = 2 * np.pi * np.arange(cols) / cols
    verts = []
    for r, hgt in prof:
        verts.append(np.stack([r * np.cos(phi), np.full(cols, hgt), r * np.sin(phi)], -1))
    verts = np.concatenate(verts)
    faces = _grid_faces(len(prof), cols, False, True)
    # The first and last profile points lie on the axis: their rings give zero-area triangles,
    # which are harmless.
    return verts, faces


_BUILDERS = {"knot": _knot, "blob": _blob, "torus": _torus, "sphere": lambda: _uv_sphere(48, 96),
             "cup": _cup, "spiky": _spiky}
BUILTIN_SHAPES = tuple(_BUILDERS)


@lru_cache(maxsize=None)
def builtin_shape(name: str) -> tuple[np.ndarray, np.ndarray]:
    """(vertices (N, 3) float32, faces (F, 3) int32) of a built-in shape, bounding radius 1."""
    if name not in _BUILDERS:
        raise RoomlightError(f"unknown built-in shape {name!r}; choose one of {', '.join(BUILTIN_SHAPES)}")
    v, f = _BUILDERS[name]()
    # Mitsuba's BSDFs shade the front side only: make every shape face outward (positive
    # signed volume) whatever winding its builder produced.
    volume = np.einsum("ij,ij->i", v[f[:, 0]], np.cross(v[f[:, 1]], v[f[:, 2]])).sum() / 6.0
    if volume < 0:
        f = f[:, [0, 2, 1]]
    v = v - 0.5 * (v.max(0) + v.min(0))
    v = v / np.linalg.norm(v, axis=1).max()
    return v.astype(np.float32), f.astype(np.int32)
