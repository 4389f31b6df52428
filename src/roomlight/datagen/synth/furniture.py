"""Furniture pieces built from boxes, cylinders and spheres, in a local frame.

Local frame: x along the piece's width (centred on 0), y up from the floor, z from the
back (z = 0, against a wall for wall pieces) to the front. Each builder returns a
:class:`Piece`; :mod:`roomlight.datagen.synth.layout` rotates it into place. Sizes in metres,
ranges from common furniture dimensions. Material names refer to
:func:`roomlight.datagen.synth.materials.room_palette`; lamp shades and screens use per-fixture
names (``shade_<k>``, ``screen_<k>``) whose materials :mod:`roomlight.datagen.synth.lights` creates.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from itertools import pairwise

import numpy as np

from roomlight.datagen.synth.materials import BOOK_MATERIALS
from roomlight.datagen.synth.spec import Box, Cylinder, Quad, Sphere

__all__ = [
    "Fixture",
    "Piece",
    "armchair",
    "bed",
    "bookshelf",
    "cabinet",
    "chair",
    "counter",
    "desk",
    "floor_lamp",
    "painting",
    "plant",
    "rug",
    "sofa",
    "table",
    "table_lamp",
    "tv_unit",
]


@dataclass
class Fixture:
    """A light-emitting part of a piece: ``kind`` (lamp, screen), material name, local centre,
    emitting area (m^2)."""

    kind: str
    material: str
    center: tuple
    area: float


@dataclass
class Piece:
    """Parts in the local frame, the footprint size (width along x, depth along z), height,
    the tops that can carry objects ``(x0, z0, x1, z1, y)`` and its light fixtures."""

    kind: str
    width: float
    depth: float
    height: float
    parts: list = field(default_factory=list)
    tops: list = field(default_factory=list)
    fixtures: list = field(default_factory=list)


def _box(x0, y0, z0, x1, y1, z1, mat, faces="xXyYzZ") -> Box:
    return Box((min(x0, x1), min(y0, y1), min(z0, z1)), (max(x0, x1), max(y0, y1), max(z0, z1)), mat, faces)


def _legs(w, d, h, mat, r=0.02, inset=0.05, z0=0.0):
    out = []
    for x in (-w / 2 + inset, w / 2 - inset):
        for z in (z0 + inset, z0 + d - inset):
            out.append(Cylinder((x, 0.0, z), r, h, mat, "top"))
    return out


def sofa(rng, mat="fabric") -> Piece:
    w, d = float(rng.uniform(1.5, 2.6)), float(rng.uniform(0.8, 1.0))
    arm, seat, back = float(rng.uniform(0.12, 0.25)), float(rng.uniform(0.38, 0.45)), float(rng.uniform(0.75, 0.95))
    p = [_box(-w / 2, 0.08, 0.01, w / 2, seat - 0.1, d, mat, "xXYzZ"),
         _box(-w / 2, seat - 0.1, 0.01, w / 2, back, 0.22, mat),
         _box(-w / 2, seat - 0.1, 0.01, -w / 2 + arm, seat + 0.2, d, mat),
         _box(w / 2 - arm, seat - 0.1, 0.01, w / 2, seat + 0.2, d, mat)]
    n = int(rng.integers(2, 4))
    xs = np.linspace(-w / 2 + arm, w / 2 - arm, n + 1)
    for a, b in pairwise(xs):
        p.append(_box(a + 0.005, seat - 0.1, 0.22, b - 0.005, seat, d - 0.01, mat))
    p += _legs(w, d, 0.08, "black", 0.02, 0.06, 0.01)
    if rng.random() < 0.6:
        for x in (-w / 2 + arm + 0.25, w / 2 - arm - 0.25):
            p.append(_box(x - 0.2, seat, 0.2, x + 0.2, seat + 0.35, 0.32, "fabric2"))
    return Piece("sofa", w, d, back, p)


def armchair(rng, mat="fabric2") -> Piece:
    w, d = float(rng.uniform(0.7, 0.95)), float(rng.uniform(0.7, 0.9))
    p = [_box(-w / 2, 0.1, 0.0, w / 2, 0.42, d, mat, "xXYzZ"), _box(-w / 2, 0.42, 0.0, w / 2, 0.9, 0.18, mat),
         _box(-w / 2, 0.42, 0.0, -w / 2 + 0.15, 0.62, d, mat), _box(w / 2 - 0.15, 0.42, 0.0, w / 2, 0.62, d, mat)]
    p += _legs(w, d, 0.1, "wood", 0.02, 0.06)
    return Piece("armchair", w, d, 0.9, p)


def bookshelf(rng, max_h: float, mat="wood") -> Piece:
    w, d = float(rng.uniform(0.6, 2.0)), float(rng.uniform(0.28, 0.4))
    h = float(min(rng.uniform(1.0, 2.2), max_h))
    t = 0.02
    p = [_box(-w / 2, 0, 0.01, -w / 2 + t, h, d, mat, "xXYzZ"), _box(w / 2 - t, 0, 0.01, w / 2, h, d, mat, "xXYzZ"),
         _box(-w / 2, h - t, 0.01, w / 2, h, d, mat), _box(-w / 2, 0, 0.01, w / 2, 0.08, d, mat, "xXYzZ"),
         _box(-w / 2, 0.08, 0.01, w / 2, h - t, 0.02, mat)]
    n = max(1, int((h - 0.1) / rng.uniform(0.3, 0.4)))
    ys = np.linspace(0.08, h - t, n + 1)
    for k, (y0, y1) in enumerate(pairwise(ys)):
        if k > 0:
            p.append(_box(-w / 2 + t, y0 - t, 0.02, w / 2 - t, y0, d, mat))
        x = -w / 2 + t + 0.01
        while x < w / 2 - t - 0.03:
            if rng.random() < 0.12:  # a gap
                x += float(rng.uniform(0.05, 0.25))
                continue
            bw = float(rng.uniform(0.02, 0.06))
            if x + bw > w / 2 - t - 0.005:
                break
            bh = float(rng.uniform(0.6, 0.92)) * (y1 - y0 - t)
            bd = float(rng.uniform(0.6, 0.95)) * (d - 0.03)
            p.append(_box(x, y0, d - bd, x + bw, y0 + bh, d - 0.005, str(rng.choice(BOOK_MATERIALS)), "xXYzZ"))
            x += bw + 0.002
    return Piece("bookshelf", w, d, h, p)


def cabinet(rng, max_h: float, tall: bool = False, mat: str | None = None) -> Piece:
    mat = mat or str(rng.choice(["wood", "painted", "white"]))
    w = float(rng.uniform(0.6, 1.2) if tall else rng.uniform(0.5, 1.8))
    d = float(rng.uniform(0.5, 0.65) if tall else rng.uniform(0.35, 0.55))
    h = float(min(rng.uniform(1.8, 2.3), max_h) if tall else rng.uniform(0.45, 1.0))
    p = [_box(-w / 2, 0.06, 0.01, w / 2, h, d, mat, "xXYzZ"), _box(-w / 2 + 0.02, 0, 0.03, w / 2 - 0.02, 0.06, d - 0.03, "black", "xXYzZ")]
    doors = max(1, round(w / 0.5))
    xs = np.linspace(-w / 2, w / 2, doors + 1)
    for a, b in pairwise(xs):
        p.append(_box(a + 0.004, 0.07, d, b - 0.004, h - 0.01, d + 0.015, mat))
        hx = b - 0.05 if (a + b) < 0 else a + 0.04
        hy = h * 0.5 if tall else h - 0.12
        p.append(_box(hx, hy - 0.06, d + 0.015, hx + 0.012, hy + 0.06, d + 0.035, "metal"))
    tops = [] if tall else [(-w / 2 + 0.05, 0.05, w / 2 - 0.05, d - 0.05, h)]
    return Piece("wardrobe" if tall else "cabinet", w, d + 0.035, h, p, tops)


def bed(rng) -> Piece:
    w = float(rng.choice([0.9, 1.4, 1.6, 1.8]) + rng.uniform(0, 0.1))
    length = float(rng.uniform(2.0, 2.15))
    hb = float(rng.uniform(0.8, 1.2))
    p = [_box(-w / 2, 0.08, 0.01, w / 2, 0.35, length, "wood", "xXYzZ"),
         _box(-w / 2, 0.0, 0.01, w / 2, hb, 0.07, "wood", "xXYzZ"),
         _box(-w / 2 + 0.03, 0.35, 0.07, w / 2 - 0.03, 0.55, length - 0.03, "white"),
         _box(-w / 2 + 0.01, 0.4, length * 0.4, w / 2 - 0.01, 0.6, length - 0.01, "fabric")]
    p += _legs(w, length - 0.01, 0.08, "black", 0.025, 0.08, 0.01)
    n = 1 if w < 1.2 else 2
    for k in range(n):
        cx = 0.0 if n == 1 else (-w / 4 if k == 0 else w / 4)
        p.append(_box(cx - min(0.35, w / 2 - 0.08), 0.55, 0.1, cx + min(0.35, w / 2 - 0.08), 0.68, 0.5, "fabric2"))
    return Piece("bed", w, length, hb, p)


def table(rng, kind: str = "dining", mat: str | None = None) -> Piece:
    mat = mat or str(rng.choice(["wood", "painted", "white"]))
    if kind == "coffee":
        w, d, h = float(rng.uniform(0.7, 1.3)), float(rng.uniform(0.45, 0.7)), float(rng.uniform(0.35, 0.45))
    elif kind == "side":
        w, d, h = float(rng.uniform(0.4, 0.55)), float(rng.uniform(0.35, 0.45)), float(rng.uniform(0.5, 0.65))
    else:
        w, d, h = float(rng.uniform(0.9, 2.0)), float(rng.uniform(0.7, 1.0)), float(rng.uniform(0.72, 0.76))
    t = 0.035
    p = [_box(-w / 2, h - t, 0, w / 2, h, d, mat)]
    if kind == "side":
        p.append(_box(-w / 2, 0.0, 0.0, w / 2, h - t, d, mat, "xXYzZ"))
    else:
        leg_mat = "metal" if rng.random() < 0.3 else mat
        p += _legs(w, d, h - t, leg_mat, 0.025, 0.06)
    return Piece(f"{kind}_table" if kind != "dining" else "table", w, d, h, p, [(-w / 2 + 0.05, 0.05, w / 2 - 0.05, d - 0.05, h)])


def chair(rng, mat: str | None = None) -> Piece:
    mat = mat or str(rng.choice(["wood", "painted", "black"]))
    w, d = 0.45, 0.45
    p = [_box(-w / 2, 0.43, 0, w / 2, 0.46, d, mat), _box(-w / 2, 0.46, 0.0, w / 2, 0.9, 0.03, mat)]
    p += _legs(w, d, 0.43, mat, 0.015, 0.03)
    return Piece("chair", w, d, 0.9, p)


def desk(rng, screen: str | None) -> Piece:
    w, d, h = float(rng.uniform(1.0, 1.6)), float(rng.uniform(0.6, 0.8)), 0.74
    mat = str(rng.choice(["wood", "white", "painted"]))
    p = [_box(-w / 2, h - 0.03, 0.01, w / 2, h, d, mat)]
    p += _legs(w, d - 0.01, h - 0.03, "metal", 0.02, 0.05, 0.01)
    fixtures = []
    if screen:
        sw = float(rng.uniform(0.5, 0.7))
        sh = sw * 9 / 16
        y0 = h + 0.12
        p += [_box(-0.03, h, 0.12, 0.03, y0, 0.16, "black"), _box(-0.12, h, 0.08, 0.12, h + 0.01, 0.25, "black"),
              _box(-sw / 2 - 0.015, y0, 0.12, sw / 2 + 0.015, y0 + sh + 0.03, 0.16, "black"),
              Quad((-sw / 2, y0 + 0.015, 0.1605), (sw, 0.0, 0.0), (0.0, sh, 0.0), screen, "local")]
        fixtures.append(Fixture("screen", screen, (0.0, y0 + sh / 2, 0.16), sw * sh))
    return Piece("desk", w, d, h, p, [(-w / 2 + 0.05, 0.3, -0.25, d - 0.05, h)], fixtures)


def tv_unit(rng, screen: str | None) -> Piece:
    base = cabinet(rng, 0.55)
    w = max(base.width, 1.0)
    p = list(base.parts)
    sw = float(min(rng.uniform(0.9, 1.6), w * 1.1))
    sh = sw * 9 / 16
    y0 = base.height + float(rng.uniform(0.15, 0.4))
    p += [_box(-sw / 2 - 0.02, y0 - 0.02, 0.02, sw / 2 + 0.02, y0 + sh + 0.02, 0.07, "black")]
    fixtures = []
    mat = screen or "black"
    p.append(Quad((-sw / 2, y0, 0.0705), (sw, 0.0, 0.0), (0.0, sh, 0.0), mat, "local"))
    if screen:
        fixtures.append(Fixture("screen", screen, (0.0, y0 + sh / 2, 0.07), sw * sh))
    return Piece("tv", base.width, base.depth, y0 + sh + 0.02, p, [], fixtures)


def counter(rng, w: float, max_h: float) -> Piece:
    d, h = 0.6, 0.9
    body = str(rng.choice(["white", "painted", "wood"]))
    top = str(rng.choice(["black", "white", "wood", "metal"]))
    p = [_box(-w / 2, 0.1, 0.01, w / 2, h - 0.04, d - 0.02, body, "xXYzZ"),
         _box(-w / 2, 0.0, 0.01, w / 2, 0.1, d - 0.07, "black", "xXYzZ"),
         _box(-w / 2, h - 0.04, 0.01, w / 2, h, d + 0.02, top)]
    for x in np.arange(-w / 2 + 0.3, w / 2, 0.6):
        p.append(_box(x - 0.15, h - 0.16, d - 0.02, x + 0.15, h - 0.14, d + 0.005, "metal"))
    if max_h > 2.3 and rng.random() < 0.8:
        p.append(_box(-w / 2, 1.45, 0.01, w / 2, min(2.2, max_h - 0.05), 0.36, body))
    return Piece("counter", w, d + 0.02, h, p, [(-w / 2 + 0.05, 0.1, w / 2 - 0.05, d - 0.05, h)])


def plant(rng) -> Piece:
    r = float(rng.uniform(0.12, 0.25))
    ph = float(rng.uniform(0.25, 0.5))
    fr = float(rng.uniform(0.2, 0.45))
    p = [Cylinder((0.0, 0.0, r), r, ph, "pot", "top"), Cylinder((0.0, ph, r), 0.02, 0.3, "wood", "none")]
    for _ in range(int(rng.integers(2, 5))):
        off = rng.uniform(-fr * 0.4, fr * 0.4, 3)
        p.append(Sphere((float(off[0]), ph + 0.3 + fr * 0.8 + float(off[1]), r + float(off[2])), fr * float(rng.uniform(0.6, 1.0)), "leaf"))
    return Piece("plant", 2 * max(r, fr), 2 * max(r, fr), ph + 0.3 + 2 * fr, p)


def rug(rng) -> Piece:
    w, d = float(rng.uniform(1.2, 3.0)), float(rng.uniform(0.8, 2.2))
    return Piece("rug", w, d, 0.012, [_box(-w / 2, 0.0, 0.0, w / 2, 0.012, d, "rug", "xXYzZ")])


def painting(rng, material: str) -> Piece:
    w = float(rng.uniform(0.35, 1.2))
    h = w * float(rng.uniform(0.6, 1.4))
    f = 0.03
    y0 = 0.0
    frame = str(rng.choice(["black", "wood", "white", "metal"]))
    p = [_box(-w / 2 - f, y0 - f, 0.005, w / 2 + f, y0, 0.035, frame), _box(-w / 2 - f, y0 + h, 0.005, w / 2 + f, y0 + h + f, 0.035, frame),
         _box(-w / 2 - f, y0, 0.005, -w / 2, y0 + h, 0.035, frame), _box(w / 2, y0, 0.005, w / 2 + f, y0 + h, 0.035, frame),
         Quad((-w / 2, y0, 0.02), (w, 0.0, 0.0), (0.0, h, 0.0), material, "local")]
    return Piece("painting", w + 2 * f, 0.035, h, p)


def floor_lamp(rng, shade: str) -> Piece:
    h = float(rng.uniform(1.3, 1.75))
    r = float(rng.uniform(0.15, 0.25))
    sh = float(rng.uniform(0.25, 0.4))
    p = [Cylinder((0.0, 0.0, r), 0.14, 0.03, "black", "top"), Cylinder((0.0, 0.03, r), 0.012, h - sh, "metal", "none"),
         Cylinder((0.0, h - sh, r), r, sh, shade, "both")]
    return Piece("floor_lamp", 2 * r, 2 * r, h, p, [], [Fixture("lamp", shade, (0.0, h - sh / 2, r), _cyl_area(r, sh))])


def table_lamp(rng, shade: str) -> Piece:
    r = float(rng.uniform(0.1, 0.18))
    sh = float(rng.uniform(0.15, 0.25))
    stem = float(rng.uniform(0.2, 0.35))
    p = [Cylinder((0.0, 0.0, r), 0.07, 0.03, "pot", "top"), Cylinder((0.0, 0.03, r), 0.01, stem, "metal", "none"),
         Cylinder((0.0, 0.03 + stem, r), r, sh, shade, "both")]
    return Piece("table_lamp", 2 * r, 2 * r, 0.03 + stem + sh, p, [],
                 [Fixture("lamp", shade, (0.0, 0.03 + stem + sh / 2, r), _cyl_area(r, sh))])


def _cyl_area(r: float, h: float) -> float:
    return float(2 * np.pi * r * h + 2 * np.pi * r * r)
