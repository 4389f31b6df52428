"""Triangulating room primitives into vertex/face arrays for ``mi.Mesh``.

Every primitive of :mod:`roomlight.datagen.synth.spec` becomes triangles whose geometric normal
``cross(p1 - p0, p2 - p0)`` points to its visible side (Mitsuba's convention), with per-vertex
shading normals (smooth on cylinders and spheres) and texture coordinates:

- ``uv = "world"``: planar world coordinates in metres divided by the material's tile size,
  so patterns (wood planks, tiles) continue seamlessly across neighbouring quads;
- ``uv = "local"``: (s, t) in [0, 1]^2 over the quad, t = 0 at the top (Mitsuba's v = 0 is the
  image's first row), for pictures and screens.
"""

from __future__ import annotations

import math

import numpy as np

from roomlight.datagen.synth.spec import Box, Cylinder, Disk, Quad, Sphere

__all__ = ["MeshArrays", "MeshBuilder"]


class MeshArrays:
    """Triangle mesh arrays: positions (V, 3), normals (V, 3), uvs (V, 2) float32, faces (F, 3) uint32."""

    def __init__(self, positions, normals, uvs, faces):
        self.positions = np.ascontiguousarray(positions, np.float32)
        self.normals = np.ascontiguousarray(normals, np.float32)
        self.uvs = np.ascontiguousarray(uvs, np.float32)
        self.faces = np.ascontiguousarray(faces, np.uint32)

    @property
    def area(self) -> float:
        """Total surface area (m^2)."""
        p = self.positions.astype(np.float64)
        f = self.faces.astype(np.int64)
        c = np.cross(p[f[:, 1]] - p[f[:, 0]], p[f[:, 2]] - p[f[:, 0]])
        return float(0.5 * np.linalg.norm(c, axis=1).sum())


class MeshBuilder:
    """Accumulates primitives into one mesh.

    Args:
        tile: metres per texture repeat for ``"world"`` uvs (1 means uv = metres).
        segments: facets around a full circle for cylinders, disks and spheres.
    """

    def __init__(self, tile: float = 1.0, segments: int = 24):
        self.tile = float(tile)
        self.segments = int(segments)
        self._p: list[np.ndarray] = []
        self._n: list[np.ndarray] = []
        self._uv: list[np.ndarray] = []
        self._f: list[np.ndarray] = []
        self._count = 0

    # -- plumbing -----------------------------------------------------------------------------
    def _append(self, p, n, uv, f):
        self._p.append(np.asarray(p, np.float64).reshape(-1, 3))
        self._n.append(np.asarray(n, np.float64).reshape(-1, 3))
        self._uv.append(np.asarray(uv, np.float64).reshape(-1, 2))
        self._f.append(np.asarray(f, np.int64).reshape(-1, 3) + self._count)
        self._count += self._p[-1].shape[0]

    def empty(self) -> bool:
        return self._count == 0

    def build(self) -> MeshArrays:
        """The accumulated mesh (raises ValueError when empty)."""
        if not self._p:
            raise ValueError("MeshBuilder.build: no primitives were added")
        return MeshArrays(np.concatenate(self._p), np.concatenate(self._n),
                          np.concatenate(self._uv), np.concatenate(self._f))

    def add(self, part) -> None:
        """Add any :data:`roomlight.datagen.synth.spec.Part`."""
        if isinstance(part, Quad):
            self.quad(part.origin, part.edge_a, part.edge_b, part.uv)
        elif isinstance(part, Box):
            self.box(part.lo, part.hi, part.faces)
        elif isinstance(part, Cylinder):
            self.cylinder(part.base, part.radius, part.height, part.caps)
        elif isinstance(part, Disk):
            self.disk(part.center, part.radius, part.facing)
        elif isinstance(part, Sphere):
            self.sphere(part.center, part.radius)
        else:  # pragma: no cover - programming error
            raise TypeError(f"MeshBuilder.add: unknown part {type(part).__name__}")

    # -- primitives ---------------------------------------------------------------------------
    def _world_uv(self, p: np.ndarray, n: np.ndarray) -> np.ndarray:
        axis = int(np.argmax(np.abs(n)))
        if axis == 1:
            uv = p[:, [0, 2]]
        elif axis == 0:
            uv = np.stack([p[:, 2], -p[:, 1]], 1)
        else:
            uv = np.stack([p[:, 0], -p[:, 1]], 1)
        return uv / self.tile

    def quad(self, origin, edge_a, edge_b, uv: str = "world") -> None:
        """Parallelogram with visible side ``edge_a x edge_b``."""
        o, a, b = (np.asarray(v, np.float64) for v in (origin, edge_a, edge_b))
        p = np.stack([o, o + a, o + a + b, o + b])
        n = np.cross(a, b)
        norm = np.linalg.norm(n)
        if norm <= 0:
            raise ValueError(f"MeshBuilder.quad: degenerate quad {origin}, {edge_a}, {edge_b}")
        n = n / norm
        if uv == "local":
            # t = 0 at the top: edge_b points up for pictures and screens.
            st = np.array([[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]])
        else:
            st = self._world_uv(p, n)
        self._append(p, np.tile(n, (4, 1)), st, [[0, 1, 2], [0, 2, 3]])

    def box(self, lo, hi, faces: str = "xXyYzZ") -> None:
        """Axis-aligned box with outward faces; ``faces`` picks them (letters ``xXyYzZ``)."""
        lo = np.asarray(lo, np.float64)
        hi = np.asarray(hi, np.float64)
        d = hi - lo
        if (d <= 0).any():
            raise ValueError(f"MeshBuilder.box: empty box {lo} .. {hi}")
        ex, ey, ez = np.diag(d)
        table = {
            "x": (lo, ez, ey),
            "X": (np.array([hi[0], lo[1], lo[2]]), ey, ez),
            "y": (lo, ex, ez),
            "Y": (np.array([lo[0], hi[1], lo[2]]), ez, ex),
            "z": (lo, ey, ex),
            "Z": (np.array([lo[0], lo[1], hi[2]]), ex, ey),
        }
        for f in faces:
            self.quad(*table[f])

    def _ring(self, r: float):
        k = max(6, round(self.segments * min(1.0, 0.25 + 2.0 * r)))
        phi = np.linspace(0.0, 2.0 * math.pi, k + 1)
        return k, phi

    def cylinder(self, base, radius: float, height: float, caps: str = "both") -> None:
        """Vertical cylinder, outward side with smooth normals, flat caps."""
        c = np.asarray(base, np.float64)
        k, phi = self._ring(radius)
        dirs = np.stack([np.cos(phi), np.zeros_like(phi), np.sin(phi)], 1)
        bottom = c + radius * dirs
        top = bottom + np.array([0.0, height, 0.0])
        p = np.concatenate([bottom, top])
        n = np.concatenate([dirs, dirs])
        s = phi * radius / self.tile
        uv = np.concatenate([np.stack([s, np.zeros_like(s)], 1),
                             np.stack([s, np.full_like(s, -height / self.tile)], 1)])
        i = np.arange(k)
        t = i + k + 1
        f = np.concatenate([np.stack([i, t, t + 1], 1), np.stack([i, t + 1, i + 1], 1)])
        self._append(p, n, uv, f)
        if caps in ("both", "top"):
            self.disk(c + np.array([0.0, height, 0.0]), radius, +1.0)
        if caps in ("both", "bottom"):
            self.disk(c, radius, -1.0)

    def disk(self, center, radius: float, facing: float = -1.0) -> None:
        """Horizontal disk facing up (``facing > 0``) or down."""
        c = np.asarray(center, np.float64)
        k, phi = self._ring(radius)
        ring = c + radius * np.stack([np.cos(phi[:k]), np.zeros(k), np.sin(phi[:k])], 1)
        p = np.concatenate([c[None], ring])
        nrm = np.array([0.0, 1.0 if facing > 0 else -1.0, 0.0])
        i = np.arange(k) + 1
        j = (np.arange(k) + 1) % k + 1
        zero = np.zeros(k, np.int64)
        f = np.stack([zero, j, i], 1) if facing > 0 else np.stack([zero, i, j], 1)
        self._append(p, np.tile(nrm, (k + 1, 1)), p[:, [0, 2]] / self.tile, f)

    def sphere(self, center, radius: float) -> None:
        """UV sphere, outward side, smooth normals."""
        c = np.asarray(center, np.float64)
        k, phi = self._ring(radius)
        rows = max(4, k // 2)
        theta = np.linspace(0.0, math.pi, rows + 1)
        tt, pp = np.meshgrid(theta, phi, indexing="ij")
        dirs = np.stack([np.sin(tt) * np.cos(pp), np.cos(tt), np.sin(tt) * np.sin(pp)], -1).reshape(-1, 3)
        p = c + radius * dirs
        uv = np.stack([pp.ravel() * radius, tt.ravel() * radius], 1) / self.tile
        idx = np.arange((rows + 1) * (k + 1)).reshape(rows + 1, k + 1)
        a, b = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel()
        cc, d = idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
        f = np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, cc], 1)])
        # Drop the degenerate triangles at the poles, then orient every face outwards.
        e = np.cross(p[f[:, 1]] - p[f[:, 0]], p[f[:, 2]] - p[f[:, 0]])
        keep = np.linalg.norm(e, axis=1) > 1e-12 * radius * radius
        f, e = f[keep], e[keep]
        centroid = p[f].mean(axis=1) - c
        flip = (e * centroid).sum(1) < 0
        f[flip] = f[flip][:, [0, 2, 1]]
        self._append(p, dirs, uv, f)
