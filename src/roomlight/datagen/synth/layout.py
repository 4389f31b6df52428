"""Placing furniture pieces in a room without collisions.

:class:`Layout` keeps the occupied floor rectangles and places :class:`~roomlight.datagen.synth.furniture.Piece`
objects against walls, free-standing, on top of other pieces, or hanging on walls. A piece is
rotated by a multiple of 90 degrees: its local z (front) maps to a horizontal axis ``n`` and
its local x to ``up x n`` (a proper rotation, so visible sides stay visible).

Rules: pieces stay inside the floor plan, 3 cm apart, outside door swings and (if taller
than the sill) in front of windows, and at least ``clearance`` metres (horizontally) from the
capture point, which therefore keeps >= 0.4 m from every surface.
"""

from __future__ import annotations

import math

import numpy as np

from roomlight.datagen.synth.furniture import Fixture, Piece
from roomlight.datagen.synth.shell import Shell, inside
from roomlight.datagen.synth.spec import Box, Cylinder, Disk, Furniture, Quad, Sphere

__all__ = ["Layout", "part_bounds", "rect_distance"]

UP = np.array([0.0, 1.0, 0.0])
_AXES = [np.array([1.0, 0.0, 0.0]), np.array([-1.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0]), np.array([0.0, 0.0, -1.0])]


def rect_distance(rect, x: float, z: float) -> float:
    """Horizontal distance from (x, z) to the rectangle (x0, z0, x1, z1) (0 inside)."""
    dx = max(rect[0] - x, 0.0, x - rect[2])
    dz = max(rect[1] - z, 0.0, z - rect[3])
    return math.hypot(dx, dz)


def part_bounds(p) -> tuple[np.ndarray, np.ndarray]:
    """Axis-aligned bounds (lo, hi) of a primitive (world or local frame)."""
    if p.shape == "box":
        return np.asarray(p.lo), np.asarray(p.hi)
    if p.shape == "quad":
        pts = np.array([p.origin, np.add(p.origin, p.edge_a), np.add(p.origin, p.edge_b),
                        np.add(np.add(p.origin, p.edge_a), p.edge_b)])
        return pts.min(0), pts.max(0)
    if p.shape == "cylinder":
        b = np.asarray(p.base)
        r = np.array([p.radius, 0.0, p.radius])
        return b - r, b + r + np.array([0.0, p.height, 0.0])
    c = np.asarray(p.center)
    r = np.full(3, p.radius)
    if p.shape == "disk":
        r[1] = 0.0
    return c - r, c + r


def _overlap(a, b, gap: float = 0.0) -> bool:
    return a[0] < b[2] + gap and b[0] < a[2] + gap and a[1] < b[3] + gap and b[1] < a[3] + gap


def _face_letter(v: np.ndarray) -> str:
    k = int(np.argmax(np.abs(v)))
    return "xyz"[k] if v[k] < 0 else "XYZ"[k]


class _Frame:
    """Local -> world map: p = origin + x * tp + y * up + z * n."""

    def __init__(self, origin, n):
        self.o = np.asarray(origin, np.float64)
        self.n = np.asarray(n, np.float64)
        self.tp = np.cross(UP, self.n)

    def point(self, p) -> np.ndarray:
        return self.o + p[0] * self.tp + p[1] * UP + p[2] * self.n

    def vec(self, v) -> np.ndarray:
        return v[0] * self.tp + v[1] * UP + v[2] * self.n

    def faces(self, local: str) -> str:
        table = {"x": -self.tp, "X": self.tp, "y": -UP, "Y": UP, "z": -self.n, "Z": self.n}
        return "".join(_face_letter(table[f]) for f in local)

    def part(self, part):
        t = lambda v: tuple(float(c) for c in v)
        if isinstance(part, Box):
            a, b = self.point(part.lo), self.point(part.hi)
            return Box(t(np.minimum(a, b)), t(np.maximum(a, b)), part.material, self.faces(part.faces))
        if isinstance(part, Cylinder):
            return Cylinder(t(self.point(part.base)), part.radius, part.height, part.material, part.caps)
        if isinstance(part, Sphere):
            return Sphere(t(self.point(part.center)), part.radius, part.material)
        if isinstance(part, Disk):
            return Disk(t(self.point(part.center)), part.radius, part.material, part.facing)
        if isinstance(part, Quad):
            return Quad(t(self.point(part.origin)), t(self.vec(part.edge_a)), t(self.vec(part.edge_b)),
                        part.material, part.uv)
        raise TypeError(type(part).__name__)


class Layout:
    """Furniture placement state for one room (see the module docstring)."""

    def __init__(self, shell: Shell, keepout: list, capture, clearance: float = 0.5):
        self.shell = shell
        self.cells = shell.cells
        self.keepout = list(keepout)
        self.capture = np.asarray(capture, np.float64)
        self.clearance = clearance
        self.occupied: list = []  # (x0, z0, x1, z1, height)
        self.hanging: list = []  # (x0, z0, x1, z1, y0, y1)
        self.furniture: list[Furniture] = []
        self.tops: list = []
        self.fixtures: list[Fixture] = []

    # -- checks -------------------------------------------------------------------------------
    def _inside(self, r) -> bool:
        for fx in (0.0, 0.5, 1.0):
            for fz in (0.0, 0.5, 1.0):
                x = r[0] + (r[2] - r[0]) * fx
                z = r[1] + (r[3] - r[1]) * fz
                x = min(max(x, r[0] + 0.005), r[2] - 0.005)
                z = min(max(z, r[1] + 0.005), r[3] - 0.005)
                if not inside(self.cells, x, z):
                    return False
        return True

    def fits(self, rect, height: float, ignore=()) -> bool:
        """Can a piece with floor ``rect`` and ``height`` go here?"""
        if not self._inside(rect):
            return False
        flat = height < 0.02
        for o in self.occupied:
            if o in ignore:
                continue
            if flat != (o[4] < 0.02):
                continue  # rugs lie under furniture
            if _overlap(rect, o, 0.03):
                return False
        if not flat:
            for k in self.keepout:
                if height > k[4] and _overlap(rect, k):
                    return False
            if rect_distance(rect, self.capture[0], self.capture[2]) < self.clearance:
                return False
        return True

    # -- committing ---------------------------------------------------------------------------
    def _realise(self, piece: Piece, frame: _Frame):
        """Floor rectangle covered by the piece: its declared footprint united with the
        bounds of all its parts (foliage, handles and overhangs included)."""
        a = frame.point((-piece.width / 2, 0.0, 0.0))
        b = frame.point((piece.width / 2, 0.0, piece.depth))
        lo = np.minimum(a, b)
        hi = np.maximum(a, b)
        for p in piece.parts:
            plo, phi = part_bounds(frame.part(p))
            lo, hi = np.minimum(lo, plo), np.maximum(hi, phi)
        return (float(lo[0]), float(lo[2]), float(hi[0]), float(hi[2]))

    def _commit(self, piece: Piece, frame: _Frame, rect) -> Furniture:
        parts = [frame.part(p) for p in piece.parts]
        lo = [rect[0], frame.o[1], rect[1]]
        hi = [rect[2], frame.o[1] + piece.height, rect[3]]
        f = Furniture(piece.kind, tuple(float(v) for v in lo), tuple(float(v) for v in hi), parts)
        self.furniture.append(f)
        self.occupied.append((*rect, frame.o[1] + piece.height))
        for x0, z0, x1, z1, y in piece.tops:
            p, q = frame.point((x0, y, z0)), frame.point((x1, y, z1))
            self.tops.append((min(p[0], q[0]), min(p[2], q[2]), max(p[0], q[0]), max(p[2], q[2]), float(p[1])))
        for fx in piece.fixtures:
            c = frame.point(fx.center)
            self.fixtures.append(Fixture(fx.kind, fx.material, tuple(float(v) for v in c), fx.area))
        return f

    def add(self, piece: Piece, origin, n) -> Furniture | None:
        """Place ``piece`` with its back centre at ``origin`` facing ``n``, if it fits."""
        frame = _Frame(origin, n)
        rect = self._realise(piece, frame)
        if not self.fits(rect, piece.height):
            return None
        return self._commit(piece, frame, rect)

    # -- strategies ---------------------------------------------------------------------------
    def on_wall(self, rng, piece: Piece, wall=None, t: float | None = None, tries: int = 20) -> Furniture | None:
        """Against a wall (random or given), at a random or given position along it."""
        walls = [wall] if wall is not None else [w for w in self.shell.walls if w.length > piece.width + 0.1]
        if not walls:
            return None
        for _ in range(tries if t is None else 1):
            w = walls[int(rng.integers(len(walls)))]
            lo, hi = w.lo + piece.width / 2 + 0.02, w.hi - piece.width / 2 - 0.02
            if hi < lo:
                continue
            tc = float(rng.uniform(lo, hi)) if t is None else t
            f = self.add(piece, w.point(tc, 0.0, 0.0), w.normal)
            if f is not None:
                f.wall = w  # type: ignore[attr-defined]
                f.t = tc  # type: ignore[attr-defined]
                return f
        return None

    def free(self, rng, piece: Piece, tries: int = 30, near=None, spread: float = 1.5) -> Furniture | None:
        """Free-standing at a random position (around ``near`` = (x, z) when given)."""
        areas = np.array([(c[2] - c[0]) * (c[3] - c[1]) for c in self.cells])
        for _ in range(tries):
            n = _AXES[int(rng.integers(4))]
            if near is None:
                c = self.cells[int(rng.choice(len(self.cells), p=areas / areas.sum()))]
                x, z = rng.uniform(c[0], c[2]), rng.uniform(c[1], c[3])
            else:
                x, z = near[0] + rng.normal(0, spread), near[1] + rng.normal(0, spread)
            f = self.add(piece, (x, 0.0, z), n)
            if f is not None:
                return f
        return None

    def around(self, rng, table: Furniture, make_chair, count: int) -> int:
        """Chairs facing the table from its four sides; returns how many fit."""
        x0, _, z0 = table.lo
        x1, _, z1 = table.hi
        cx, cz = 0.5 * (x0 + x1), 0.5 * (z0 + z1)
        spots = []
        for n, (px, pz), span in [(_AXES[2], (cx, z0 - 0.5), x1 - x0), (_AXES[3], (cx, z1 + 0.5), x1 - x0),
                                  (_AXES[0], (x0 - 0.5, cz), z1 - z0), (_AXES[1], (x1 + 0.5, cz), z1 - z0)]:
            k = max(1, int(span // 0.6))
            for j in range(k):
                off = (j + 0.5) / k * span - span / 2
                p = (px + (off if abs(n[2]) > 0 else 0.0), 0.0, pz + (off if abs(n[0]) > 0 else 0.0))
                spots.append((p, n))
        placed = 0
        for i in rng.permutation(len(spots)):
            if placed >= count:
                break
            p, n = spots[i]
            if self.add(make_chair(), p, n) is not None:
                placed += 1
        return placed

    def on_top(self, rng, piece: Piece, tries: int = 10) -> Furniture | None:
        """On a free top surface (tables, cabinets) big enough for the piece."""
        for _ in range(tries):
            if not self.tops:
                return None
            top = self.tops[int(rng.integers(len(self.tops)))]
            x0, z0, x1, z1, y = top
            r = max(piece.width, piece.depth) / 2
            if x1 - x0 < 2 * r or z1 - z0 < 2 * r:
                continue
            x, z = rng.uniform(x0 + r, x1 - r), rng.uniform(z0 + r, z1 - r)
            n = _AXES[int(rng.integers(4))]
            frame = _Frame((x, y, z), n)
            frame.o = frame.o - frame.n * (piece.depth / 2)
            rect = self._realise(piece, frame)
            if rect_distance(rect, self.capture[0], self.capture[2]) < self.clearance:
                continue
            self.tops.remove(top)
            f = self._commit(piece, frame, rect)
            self.occupied.pop()  # objects on top do not block the floor
            return f
        return None

    def hang(self, rng, piece: Piece, tries: int = 15) -> Furniture | None:
        """On a wall (paintings): centre 1.2-1.7 m high, clear of openings, tall furniture
        and other hanging pieces."""
        walls = [w for w in self.shell.walls if w.length > piece.width + 0.3]
        for _ in range(tries):
            if not walls:
                return None
            w = walls[int(rng.integers(len(walls)))]
            tc = float(rng.uniform(w.lo + piece.width / 2 + 0.1, w.hi - piece.width / 2 - 0.1))
            y0 = float(rng.uniform(1.2, 1.7)) - piece.height / 2
            y1 = y0 + piece.height
            if y1 > self.shell.height - 0.15:
                continue
            t0, t1 = tc - piece.width / 2, tc + piece.width / 2
            if not w.free(t0, t1, y0, y1, 0.1):
                continue
            a, b = w.point(t0, 0.0, 0.0), w.point(t1, 0.0, -0.1)
            rect = (min(a[0], b[0]), min(a[2], b[2]), max(a[0], b[0]), max(a[2], b[2]))
            if any(o[4] > y0 - 0.05 and _overlap(rect, o) for o in self.occupied):
                continue
            if any(h[4] < y1 and h[5] > y0 and _overlap(rect, h, 0.15) for h in self.hanging):
                continue
            frame = _Frame(w.point(tc, y0 + piece.height * 0.0 + 0.03, 0.0), w.normal)
            f = self._commit(piece, frame, rect)
            self.occupied.pop()
            self.hanging.append((*rect, y0, y1))
            return f
        return None
