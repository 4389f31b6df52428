"""Room shells: floor plans (box, L-shape, alcove), their walls, and walls with holes.

A floor plan is a list of disjoint axis-aligned rectangles ("cells", ``(x0, z0, x1, z1)`` in
metres) on the floor y = 0; the room is their union extruded to the ceiling height. Its walls
are the boundary edges of the union, found generically (so any union of rectangles works),
each a :class:`WallSeg` on the plane ``x = c`` (``axis = 0``) or ``z = c`` (``axis = 2``)
with an inward normal. Openings are rectangles ``(t0, t1, y0, y1)`` on a wall, ``t`` being the
horizontal coordinate along it (z for axis 0, x for axis 2).

Shell quads are enlarged by :data:`OVERLAP` (1 mm) along their edges so that neighbouring
quads overlap instead of meeting edge-to-edge, which keeps rays from slipping through cracks.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from itertools import pairwise

import numpy as np

from roomlight.datagen.synth.spec import Quad

__all__ = [
    "OVERLAP",
    "Shell",
    "WallSeg",
    "distance_to_walls",
    "floor_ceiling_quads",
    "inside",
    "oriented_quad",
    "plan_walls",
    "sample_shell",
    "wall_quads",
]

OVERLAP = 1e-3


@dataclass
class WallSeg:
    """One straight wall: plane ``axis``-coordinate = ``c``, spanning ``lo..hi`` along ``t`` and
    the floor-to-ceiling height; ``sign`` gives the inward normal ``sign * e_axis``."""

    axis: int
    c: float
    lo: float
    hi: float
    sign: int
    openings: list = field(default_factory=list)  # (t0, t1, y0, y1)

    @property
    def length(self) -> float:
        return self.hi - self.lo

    @property
    def normal(self) -> np.ndarray:
        n = np.zeros(3)
        n[self.axis] = self.sign
        return n

    @property
    def tangent(self) -> np.ndarray:
        t = np.zeros(3)
        t[2 if self.axis == 0 else 0] = 1.0
        return t

    def point(self, t: float, y: float, out: float = 0.0) -> np.ndarray:
        """World point at (t, y) on the wall, moved ``out`` metres outwards (away from the room)."""
        p = np.zeros(3)
        p[self.axis] = self.c - self.sign * out
        p[2 if self.axis == 0 else 0] = t
        p[1] = y
        return p

    def free(self, t0: float, t1: float, y0: float = -1e9, y1: float = 1e9, gap: float = 0.0) -> bool:
        """True when ``[t0, t1] x [y0, y1]`` (grown by ``gap``) overlaps no opening."""
        for a0, a1, b0, b1 in self.openings:
            if t0 < a1 + gap and t1 > a0 - gap and y0 < b1 and y1 > b0:
                return False
        return True


@dataclass
class Shell:
    """A floor plan extruded to ``height``, its walls and wall thickness (reveal depth)."""

    kind: str
    cells: list
    height: float
    thickness: float
    walls: list = field(default_factory=list)


def inside(cells, x: float, z: float, margin: float = 0.0) -> bool:
    """Is (x, z) inside the union of ``cells`` (each shrunk by ``margin``)?"""
    return any(x0 + margin < x < x1 - margin and z0 + margin < z < z1 - margin for x0, z0, x1, z1 in cells)


def plan_walls(cells) -> list[WallSeg]:
    """Boundary walls of the union of disjoint rectangles, merged into maximal segments."""
    eps = 1e-6
    xs = sorted({c[0] for c in cells} | {c[2] for c in cells})
    zs = sorted({c[1] for c in cells} | {c[3] for c in cells})
    pieces: dict[tuple, list] = {}
    for x0, z0, x1, z1 in cells:
        # (axis, plane coordinate, sign of the inward normal, t range, breakpoints along t)
        sides = [(0, x0, +1, z0, z1, zs), (0, x1, -1, z0, z1, zs),
                 (2, z0, +1, x0, x1, xs), (2, z1, -1, x0, x1, xs)]
        for axis, c, sign, lo, hi, breaks in sides:
            cuts = [lo] + [b for b in breaks if lo + eps < b < hi - eps] + [hi]
            for a, b in pairwise(cuts):
                m = 0.5 * (a + b)
                probe = c - sign * 1e-4
                outside = not (inside(cells, probe, m) if axis == 0 else inside(cells, m, probe))
                if outside:
                    pieces.setdefault((axis, round(c, 9), sign), []).append((a, b))
    walls = []
    for (axis, c, sign), segs in sorted(pieces.items()):
        segs.sort()
        cur = list(segs[0])
        for a, b in segs[1:]:
            if abs(a - cur[1]) < eps:
                cur[1] = b
            else:
                walls.append(WallSeg(axis, c, cur[0], cur[1], sign))
                cur = [a, b]
        walls.append(WallSeg(axis, c, cur[0], cur[1], sign))
    return walls


def distance_to_walls(walls, x: float, z: float) -> float:
    """Horizontal distance from (x, z) to the nearest wall segment."""
    best = math.inf
    for w in walls:
        px, pt = (x, z) if w.axis == 0 else (z, x)
        dt = max(w.lo - pt, 0.0, pt - w.hi)
        best = min(best, math.hypot(px - w.c, dt))
    return best


def _size(rng: np.random.Generator, mean: float, lo: float, hi: float) -> float:
    return float(np.clip(math.exp(rng.normal(math.log(mean), 0.3)), lo, hi))


def sample_shell(rng: np.random.Generator) -> Shell:
    """A random floor plan: box (42 %), L-shape (22 %), box with an alcove (21 %) or a large
    space (15 %: hall, lobby, open-plan office, workshop, warehouse).

    Ordinary rooms: sides 2.2-12 m (median ~4-6 m), ceiling 2.3-4 m (mostly 2.4-3 m). Large
    spaces: sides 9-30 m (median ~14 m), ceiling 3.5-8 m, log-uniform so that lobbies and
    warehouses are as likely as halls. Walls are 0.12-0.35 m thick. The first cell is always
    the main (largest) one.
    """
    u = rng.random()
    height = float(np.clip(rng.normal(2.75, 0.35), 2.3, 4.0))
    thickness = float(rng.uniform(0.12, 0.35))
    if u < 0.42:
        kind = "box"
        x, z = _size(rng, 4.5, 2.2, 12.0), _size(rng, 4.0, 2.2, 12.0)
        cells = [(0.0, 0.0, x, z)]
    elif u < 0.64:
        kind = "L"
        x, z = _size(rng, 6.5, 4.0, 12.0), _size(rng, 6.0, 4.0, 12.0)
        nx, nz = x * rng.uniform(0.3, 0.55), z * rng.uniform(0.3, 0.55)
        cells = [(0.0, 0.0, x, z - nz), (0.0, z - nz, x - nx, z)]
    elif u < 0.85:
        kind = "alcove"
        x, z = _size(rng, 4.5, 2.8, 12.0), _size(rng, 4.0, 2.4, 12.0)
        w = float(rng.uniform(1.0, min(3.0, x - 0.8)))
        d = float(rng.uniform(0.6, 1.6))
        x0 = float(rng.uniform(0.4, x - w - 0.4))
        cells = [(0.0, 0.0, x, z), (x0, z, x0 + w, z + d)]
    else:
        kind = "large"
        height = float(math.exp(rng.uniform(math.log(3.5), math.log(8.0))))
        x, z = _size(rng, 15.0, 9.0, 30.0), _size(rng, 13.0, 9.0, 30.0)
        cells = [(0.0, 0.0, x, z)]
    cells = [tuple(round(float(v), 4) for v in c) for c in cells]
    return Shell(kind, cells, round(height, 4), round(thickness, 4), plan_walls(cells))


def oriented_quad(origin, edge_a, edge_b, normal, material: str, uv: str = "world",
                  grow: float = 0.0) -> Quad:
    """A :class:`Quad` whose visible side faces ``normal`` (edge_b keeps its direction, so
    local uvs stay upright), optionally grown by ``grow`` metres on every side."""
    o, a, b = (np.asarray(v, np.float64) for v in (origin, edge_a, edge_b))
    if np.dot(np.cross(a, b), np.asarray(normal, np.float64)) < 0:
        o, a = o + a, -a
    if grow > 0:
        ua, ub = a / np.linalg.norm(a), b / np.linalg.norm(b)
        o = o - grow * (ua + ub)
        a = a + 2 * grow * ua
        b = b + 2 * grow * ub
    return Quad(tuple(o.tolist()), tuple(a.tolist()), tuple(b.tolist()), material, uv)


def wall_quads(wall: WallSeg, height: float, material: str, y_lo: float = 0.0, flip: bool = False,
               out: float = 0.0) -> list[Quad]:
    """Quads covering the wall except its openings (a grid split at the openings' edges).

    ``flip`` makes them face outwards (used for the far side of a wall seen from an adjacent
    space, together with ``out`` = the wall thickness).
    """
    ts = sorted({wall.lo, wall.hi} | {v for o in wall.openings for v in o[:2]})
    ys = sorted({y_lo, height} | {v for o in wall.openings for v in o[2:] if y_lo < v < height})
    n = -wall.normal if flip else wall.normal
    quads = []
    for ta, tb in pairwise(ts):
        for ya, yb in pairwise(ys):
            if tb - ta < 1e-6 or yb - ya < 1e-6:
                continue
            tm, ym = 0.5 * (ta + tb), 0.5 * (ya + yb)
            if any(o[0] < tm < o[1] and o[2] < ym < o[3] for o in wall.openings):
                continue
            o = wall.point(ta, ya, out)
            quads.append(oriented_quad(o, wall.tangent * (tb - ta), np.array([0.0, yb - ya, 0.0]), n,
                                       material, grow=OVERLAP))
    return quads


def floor_ceiling_quads(cells, height: float, floor: str, ceiling: str) -> list[Quad]:
    """One floor quad (facing up) and one ceiling quad (facing down) per cell."""
    quads = []
    for x0, z0, x1, z1 in cells:
        ex, ez = np.array([x1 - x0, 0.0, 0.0]), np.array([0.0, 0.0, z1 - z0])
        quads.append(oriented_quad((x0, 0.0, z0), ex, ez, (0, 1, 0), floor, grow=OVERLAP))
        quads.append(oriented_quad((x0, height, z0), ex, ez, (0, -1, 0), ceiling, grow=OVERLAP))
    return quads
