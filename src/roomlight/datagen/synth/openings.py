"""Windows and doors: placing them on walls and building their geometry.

A window is a hole in a wall with reveals (the wall's thickness), a frame with optional
mullions near the outer face, and a *portal* at the outer face through which the outdoor
environment shines (:mod:`roomlight.datagen.synth.portal`). A door is closed (a leaf with a handle)
or open onto an adjacent space: a closed box behind the wall (hallway, next room) with its
own materials and, sometimes, its own light (added by :mod:`roomlight.datagen.synth.lights`).

Materials referenced by name: ``wall``, ``frame``, ``door``, ``metal``, ``adj_wall``,
``adj_floor``, ``adj_ceiling`` (see :mod:`roomlight.datagen.synth.materials`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from roomlight.datagen.synth.shell import OVERLAP, Shell, WallSeg, oriented_quad, wall_quads
from roomlight.datagen.synth.spec import Box, Door, Window

__all__ = ["Openings", "box_on_wall", "place_openings"]

UP = np.array([0.0, 1.0, 0.0])


@dataclass
class Openings:
    """Result of :func:`place_openings`.

    ``keepout``: floor rectangles ``(x0, z0, x1, z1, max_height)`` that furniture taller than
    ``max_height`` must not overlap (door swings: 0; below windows: the sill height).
    ``spaces``: adjacent spaces ``(x0, z0, x1, z1, height)``; ``blocked``: floor rectangles
    outside the room already used (reveals, spaces), for overlap checks.
    """

    windows: list = field(default_factory=list)
    doors: list = field(default_factory=list)
    parts: list = field(default_factory=list)
    keepout: list = field(default_factory=list)
    spaces: list = field(default_factory=list)
    blocked: list = field(default_factory=list)


def _rect(p, q, grow: float = 0.0):
    return (min(p[0], q[0]) - grow, min(p[2], q[2]) - grow, max(p[0], q[0]) + grow, max(p[2], q[2]) + grow)


def _overlap(a, b) -> bool:
    return a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]


def box_on_wall(w: WallSeg, t0, t1, y0, y1, out0, out1, material: str, faces: str = "xXyYzZ") -> Box:
    """Axis-aligned box given in wall coordinates (t along the wall, y up, ``out`` outwards)."""
    p, q = w.point(t0, y0, out0), w.point(t1, y1, out1)
    return Box(tuple(np.minimum(p, q).tolist()), tuple(np.maximum(p, q).tolist()), material, faces)


def _reveal(w: WallSeg, t0, t1, y0, y1, depth, material) -> list:
    """The four faces lining a hole through a wall of thickness ``depth``, facing the hole."""
    out = -w.normal * depth
    tan = w.tangent
    return [
        oriented_quad(w.point(t0, y0), UP * (y1 - y0), out, tan, material, grow=OVERLAP),
        oriented_quad(w.point(t1, y0), UP * (y1 - y0), out, -tan, material, grow=OVERLAP),
        oriented_quad(w.point(t0, y0), tan * (t1 - t0), out, UP, material, grow=OVERLAP),
        oriented_quad(w.point(t0, y1), tan * (t1 - t0), out, -UP, material, grow=OVERLAP),
    ]


def _slot(rng, w: WallSeg, width: float, y0: float, y1: float, margin: float = 0.15, gap: float = 0.3):
    """A free position (t0, t1) for an opening of ``width`` on ``w``, or None."""
    lo, hi = w.lo + margin, w.hi - margin - width
    if hi <= lo:
        return None
    for _ in range(12):
        t0 = float(rng.uniform(lo, hi))
        if w.free(t0, t0 + width, y0, y1, gap):
            return t0, t0 + width
    return None


def _window(rng, shell: Shell, w: WallSeg, ops: Openings) -> bool:
    h = shell.height
    # Window sizes grow with the room: small punched windows up to curtain walls. In a tall
    # room a window may also be a clerestory band high on the wall (light from above the eye).
    tall = h > 3.4
    u = rng.random()
    if u < 0.15:  # floor-to-ceiling glazing
        y0, y1 = 0.05, h - float(rng.uniform(0.05, 0.35))
    elif tall and u < 0.35:  # clerestory
        y0 = float(rng.uniform(0.5, 0.75)) * h
        y1 = min(h - float(rng.uniform(0.1, 0.4)), y0 + float(rng.uniform(0.6, 2.0)))
    else:
        y0 = float(rng.uniform(0.4, 1.0))
        span_hi = max(2.0, 0.6 * h) if tall else 2.0
        y1 = min(h - float(rng.uniform(0.1, 0.4)), y0 + float(rng.uniform(0.8, span_hi)))
    if y1 - y0 < 0.5:
        return False
    max_width = 2.8 if not tall else min(8.0, 2.8 * h / 3.0)
    width = float(rng.uniform(0.5, max(0.6, min(max_width, 0.8 * w.length))))
    slot = _slot(rng, w, width, y0, y1)
    if slot is None:
        return False
    t0, t1 = slot
    d = shell.thickness
    footprint = _rect(w.point(t0, 0, 0), w.point(t1, 0, d + 0.05))
    if any(_overlap(footprint, b) for b in ops.blocked):
        return False
    w.openings.append((t0, t1, y0, y1))
    ops.blocked.append(footprint)
    ops.windows.append(Window(tuple(w.point(t0, y0).tolist()), tuple((w.tangent * (t1 - t0)).tolist()),
                              tuple((UP * (y1 - y0)).tolist()), tuple(w.normal.tolist()), d))
    ops.parts += _reveal(w, t0, t1, y0, y1, d, "wall")
    # Frame and mullions just inside the portal.
    fw, o0, o1 = 0.05, d - 0.07, d - 0.005
    frame = [(t0, t0 + fw, y0, y1), (t1 - fw, t1, y0, y1), (t0, t1, y0, y0 + fw), (t0, t1, y1 - fw, y1)]
    if t1 - t0 > 1.0 and rng.random() < 0.7:
        tm = 0.5 * (t0 + t1)
        frame.append((tm - fw / 2, tm + fw / 2, y0, y1))
    if y1 - y0 > 1.4 and rng.random() < 0.4:
        ym = y0 + 0.7 * (y1 - y0)
        frame.append((t0, t1, ym - fw / 2, ym + fw / 2))
    ops.parts += [box_on_wall(w, a, b, c, e, o0, o1, "frame") for a, b, c, e in frame]
    if y0 > 0.3 and rng.random() < 0.6:  # sill board
        ops.parts.append(box_on_wall(w, t0 - 0.05, t1 + 0.05, y0 - 0.03, y0, -0.04, 0.0, "frame"))
    ops.keepout.append((*_rect(w.point(t0 - 0.05, 0, 0), w.point(t1 + 0.05, 0, -0.9)), y0 - 0.02))
    return True


def _space_parts(w: WallSeg, ta, tb, d, depth, height, hole) -> list:
    """Floor, ceiling and walls of an adjacent space behind wall ``w`` (out = d .. d + depth)."""
    parts = []
    near = WallSeg(w.axis, w.c - w.sign * d, ta, tb, -w.sign, [hole])
    parts += wall_quads(near, height, "adj_wall")
    far = WallSeg(w.axis, w.c - w.sign * (d + depth), ta, tb, w.sign)
    parts += wall_quads(far, height, "adj_wall")
    tan, out = w.tangent, -w.normal * depth
    parts.append(oriented_quad(w.point(ta, 0, d), UP * height, out, tan, "adj_wall", grow=OVERLAP))
    parts.append(oriented_quad(w.point(tb, 0, d), UP * height, out, -tan, "adj_wall", grow=OVERLAP))
    parts.append(oriented_quad(w.point(ta, 0, d), tan * (tb - ta), out, UP, "adj_floor", grow=OVERLAP))
    parts.append(oriented_quad(w.point(ta, height, d), tan * (tb - ta), out, -UP, "adj_ceiling", grow=OVERLAP))
    return parts


def _door(rng, shell: Shell, w: WallSeg, ops: Openings, cells) -> bool:
    h = shell.height
    wide = rng.random() < 0.3
    width = float(rng.uniform(1.1, 2.2) if wide else rng.uniform(0.8, 0.95))
    y1 = min(h - 0.1, float(rng.uniform(2.0, 2.2)) if not wide else float(rng.uniform(2.0, h - 0.1)))
    slot = _slot(rng, w, width, 0.0, y1, margin=0.1)
    if slot is None:
        return False
    t0, t1 = slot
    d = shell.thickness
    state = "open" if wide or rng.random() < 0.5 else "closed"
    space = None
    if state == "open":
        depth = float(rng.uniform(1.2, 4.0))
        ta, tb = t0 - float(rng.uniform(0.3, 2.0)), t1 + float(rng.uniform(0.3, 2.0))
        rect = _rect(w.point(ta, 0, d), w.point(tb, 0, d + depth))
        clash = any(_overlap(rect, c) for c in cells) or any(_overlap(rect, b) for b in ops.blocked)
        if clash:
            if wide:
                return False
            state = "closed"
        else:
            space = (*rect, h)
    footprint = _rect(w.point(t0, 0, 0), w.point(t1, 0, d))
    if any(_overlap(footprint, b) for b in ops.blocked):
        return False
    w.openings.append((t0, t1, 0.0, y1))
    ops.blocked.append(footprint)
    ops.parts += _reveal(w, t0, t1, 0.0, y1, d, "wall")
    if state == "closed":
        leaf_out = min(0.04, d / 2)
        ops.parts.append(oriented_quad(w.point(t0, 0, leaf_out), w.tangent * (t1 - t0), UP * y1, w.normal,
                                       "door", grow=OVERLAP))
        th = t1 - 0.09 if rng.random() < 0.5 else t0 + 0.07
        ops.parts.append(box_on_wall(w, th, th + 0.02, 0.98, 1.03, -0.07, leaf_out, "metal"))
    else:
        ops.blocked.append(space[:4])
        ops.spaces.append(space)
        ops.parts += _space_parts(w, ta, tb, d, depth, h, (t0, t1, 0.0, y1))
    # Casing around the opening on the room side.
    cw = 0.07
    for a, b, c, e in [(t0 - cw, t0, 0.0, y1 + cw), (t1, t1 + cw, 0.0, y1 + cw), (t0 - cw, t1 + cw, y1, y1 + cw)]:
        if a >= w.lo and b <= w.hi and e <= h:
            ops.parts.append(box_on_wall(w, a, b, c, e, -0.015, 0.0, "frame"))
    ops.doors.append(Door(tuple(w.point(t0, 0).tolist()), tuple((w.tangent * (t1 - t0)).tolist()),
                          tuple((UP * y1).tolist()), tuple(w.normal.tolist()), d, state, space))
    ops.keepout.append((*_rect(w.point(t0 - 0.1, 0, 0), w.point(t1 + 0.1, 0, -1.0)), 0.0))
    return True


def place_openings(rng: np.random.Generator, shell: Shell, n_windows: int, n_doors: int) -> Openings:
    """Place up to ``n_windows`` windows on one or two facade walls and up to ``n_doors`` doors
    on the other walls (any wall when there is no other). Fewer are placed when walls are full;
    the caller checks ``len(result.windows)``."""
    ops = Openings()
    cells = shell.cells
    walls = [w for w in shell.walls if w.length >= 1.0]
    order = list(rng.permutation(len(walls)))
    n_facade = 1 if rng.random() < 0.6 or len(walls) < 3 else 2
    facade = [walls[i] for i in order[:n_facade]]
    others = [walls[i] for i in order[n_facade:]] or facade
    for k in range(n_windows):
        for attempt in range(4):
            w = facade[(k + attempt) % len(facade)]
            if _window(rng, shell, w, ops):
                break
    for k in range(n_doors):
        for attempt in range(4):
            w = others[int(rng.integers(len(others)))]
            if _door(rng, shell, w, ops, cells):
                break
    return ops
