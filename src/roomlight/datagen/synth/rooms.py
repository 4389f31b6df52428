"""The seeded room generator: shell, openings, capture point, materials, furniture, lights.

``generate_room(seed)`` is deterministic: the same seed (and :data:`GENERATOR_VERSION`) always
gives the same :class:`~roomlight.datagen.synth.spec.Room`. Room types (probability): living 0.3,
bedroom 0.25, office 0.2, kitchen 0.15, hall 0.1, each with its own furnishing program; large
spaces (the ``large`` shell) get the ``large`` program (lobby, open-plan office, workshop or
warehouse clutter, scaled with the floor area).
"""

from __future__ import annotations

import math

import numpy as np

from roomlight.datagen.synth import furniture as fu
from roomlight.datagen.synth.layout import Layout, part_bounds
from roomlight.datagen.synth.lights import (
    SKY_OF,
    ceiling_lights,
    fixture_materials,
    lights_on_probability,
    sample_scenario,
    space_lights,
    window_count,
)
from roomlight.datagen.synth.materials import CANVAS_MATERIALS, concrete_floor, room_palette
from roomlight.datagen.synth.openings import place_openings
from roomlight.datagen.synth.shell import (
    floor_ceiling_quads,
    plan_walls,
    sample_shell,
    wall_quads,
)
from roomlight.datagen.synth.sky import sample_sky
from roomlight.datagen.synth.spec import Room

__all__ = ["ROOM_TYPES", "box_room", "capture_clearance", "generate_room"]

ROOM_TYPES = {"living": 0.3, "bedroom": 0.25, "office": 0.2, "kitchen": 0.15, "hall": 0.1}
_SALT = 0x526F6F6D  # "Room": separates this stream from other uses of the same seed


class _Names:
    """Unique fixture material names (``shade_0``, ``screen_1``...)."""

    def __init__(self):
        self.counts: dict[str, int] = {}

    def __call__(self, prefix: str) -> str:
        k = self.counts.get(prefix, 0)
        self.counts[prefix] = k + 1
        return f"{prefix}_{k}"


def _living(rng, lay: Layout, names, height):
    sofa = lay.on_wall(rng, fu.sofa(rng))
    lay.on_wall(rng, fu.tv_unit(rng, names("screen")))
    if sofa is not None:
        front = np.array([(sofa.lo[0] + sofa.hi[0]) / 2, (sofa.lo[2] + sofa.hi[2]) / 2])
        lay.free(rng, fu.table(rng, "coffee"), near=front, spread=0.8)
        if rng.random() < 0.5:
            lay.free(rng, fu.floor_lamp(rng, names("shade")), near=front, spread=1.2)
    if rng.random() < 0.5:
        lay.free(rng, fu.armchair(rng))
    if rng.random() < 0.6:
        lay.on_wall(rng, fu.bookshelf(rng, height - 0.1))
    if rng.random() < 0.4:
        lay.on_wall(rng, fu.cabinet(rng, height - 0.1))
    if rng.random() < 0.4:
        lay.free(rng, fu.table(rng, "side"))
    if rng.random() < 0.6:
        lay.free(rng, fu.rug(rng))
    for _ in range(int(rng.integers(0, 3))):
        lay.free(rng, fu.plant(rng))
    if rng.random() < 0.5:
        lay.on_top(rng, fu.table_lamp(rng, names("shade")))


def _bedroom(rng, lay: Layout, names, height):
    bed = None
    for _ in range(3):
        bed = lay.on_wall(rng, fu.bed(rng))
        if bed is not None:
            break
    if bed is not None:
        width = _extent_along(bed)
        for side in (-1, 1):
            if rng.random() < 0.8:
                ns = fu.table(rng, "side")
                t = bed.t + side * (width / 2 + ns.width / 2 + 0.05)
                lay.on_wall(rng, ns, wall=bed.wall, t=t)
        for _ in range(2):
            if rng.random() < 0.7:
                lay.on_top(rng, fu.table_lamp(rng, names("shade")))
    if rng.random() < 0.7:
        lay.on_wall(rng, fu.cabinet(rng, height - 0.1, tall=True))
    if rng.random() < 0.4:
        d = lay.on_wall(rng, fu.desk(rng, names("screen") if rng.random() < 0.5 else None))
        if d is not None:
            lay.around(rng, d, lambda: fu.chair(rng), 1)
    if rng.random() < 0.5:
        lay.free(rng, fu.rug(rng))
    if rng.random() < 0.4:
        lay.free(rng, fu.plant(rng))


def _office(rng, lay: Layout, names, height):
    for _ in range(int(rng.integers(1, 5))):
        d = fu.desk(rng, names("screen") if rng.random() < 0.8 else None)
        f = lay.on_wall(rng, d) if rng.random() < 0.6 else lay.free(rng, d)
        if f is not None:
            lay.around(rng, f, lambda: fu.chair(rng, "black"), 1)
    for _ in range(int(rng.integers(1, 3))):
        lay.on_wall(rng, fu.bookshelf(rng, height - 0.1))
    if rng.random() < 0.6:
        lay.on_wall(rng, fu.cabinet(rng, height - 0.1))
    if rng.random() < 0.6:
        lay.free(rng, fu.plant(rng))
    if rng.random() < 0.4:
        lay.on_top(rng, fu.table_lamp(rng, names("shade")))


def _kitchen(rng, lay: Layout, names, height):
    for w in (3.0, 2.4, 1.8, 1.2):
        if lay.on_wall(rng, fu.counter(rng, w + float(rng.uniform(0, 0.6)), height)) is not None:
            break
    t = lay.free(rng, fu.table(rng, "dining"))
    if t is not None:
        lay.around(rng, t, lambda: fu.chair(rng), int(rng.integers(2, 7)))
    if rng.random() < 0.4:
        lay.on_wall(rng, fu.cabinet(rng, height - 0.1, tall=True))
    if rng.random() < 0.3:
        lay.free(rng, fu.plant(rng))


def _hall(rng, lay: Layout, names, height):
    if rng.random() < 0.6:
        lay.on_wall(rng, fu.cabinet(rng, height - 0.1))
    if rng.random() < 0.6:
        lay.free(rng, fu.plant(rng))
    if rng.random() < 0.4:
        lay.free(rng, fu.rug(rng))
    if rng.random() < 0.4:
        lay.on_top(rng, fu.table_lamp(rng, names("shade")))


def _large(rng, lay: Layout, names, height):
    """Clutter of a large space, by kind: lobby (seating islands, plants), open-plan office
    (desk clusters), workshop (benches, shelving) or warehouse (rows of tall racks).
    The number of pieces grows with the floor area (about one per 8-15 m^2)."""
    area = sum((c[2] - c[0]) * (c[3] - c[1]) for c in lay.cells)
    kind = str(rng.choice(["lobby", "open_office", "workshop", "warehouse"]))
    n = int(area / float(rng.uniform(8.0, 15.0)))
    shelf_h = min(height - 0.1, float(rng.uniform(2.0, 3.5)))
    for _ in range(n):
        u = rng.random()
        if kind == "lobby":
            piece = (fu.sofa(rng) if u < 0.3 else fu.armchair(rng) if u < 0.5 else fu.plant(rng) if u < 0.75
                     else fu.table(rng, "coffee"))
        elif kind == "open_office":
            piece = (fu.desk(rng, names("screen") if rng.random() < 0.7 else None) if u < 0.55
                     else fu.chair(rng, "black") if u < 0.75 else fu.plant(rng) if u < 0.85 else fu.cabinet(rng, 1.3))
        elif kind == "workshop":
            piece = (fu.table(rng, "dining", "metal") if u < 0.4 else fu.cabinet(rng, shelf_h, tall=True, mat="metal")
                     if u < 0.7 else fu.bookshelf(rng, shelf_h, "metal"))
        else:
            piece = fu.bookshelf(rng, shelf_h, "metal") if u < 0.6 else fu.cabinet(rng, 1.6, mat="wood")
        if rng.random() < 0.35:
            lay.on_wall(rng, piece)
        else:
            lay.free(rng, piece)
    if rng.random() < 0.5:
        lay.free(rng, fu.rug(rng))


_PROGRAMS = {"living": _living, "bedroom": _bedroom, "office": _office, "kitchen": _kitchen, "hall": _hall,
             "large": _large}


def _extent_along(f) -> float:
    """Width of a wall piece along its wall."""
    w = f.wall
    return (f.hi[2] - f.lo[2]) if w.axis == 0 else (f.hi[0] - f.lo[0])


def _capture(rng, shell) -> tuple[float, float, float]:
    x0, z0, x1, z1 = shell.cells[0]
    m = 0.5
    x = float(rng.uniform(x0 + m, x1 - m))
    z = float(rng.uniform(z0 + m, z1 - m))
    y = float(rng.uniform(0.9, min(1.8, shell.height - 0.5)))
    return (round(x, 4), round(y, 4), round(z, 4))


def _sun_in_view(rng, windows, capture):
    """A sun direction seen through a window from the capture point (elevation 8-65 deg), or None."""
    c = np.asarray(capture, np.float64)
    for _ in range(8):
        w = windows[int(rng.integers(len(windows)))]
        s, t = rng.uniform(0.1, 0.9), rng.uniform(0.3, 0.95)
        p = np.asarray(w.origin) + s * np.asarray(w.edge_a) + t * np.asarray(w.edge_b) - np.asarray(w.normal) * w.depth
        d = (p - c) / np.linalg.norm(p - c)
        if math.sin(math.radians(8)) < d[1] < math.sin(math.radians(65)):
            return tuple(float(v) for v in d)
    return None


def capture_clearance(room: Room) -> float:
    """Smallest distance (m) from the capture point to any part's bounding box or the shell."""
    from roomlight.datagen.synth.shell import distance_to_walls

    c = np.asarray(room.capture)
    best = min(distance_to_walls(plan_walls(room.cells), c[0], c[2]), c[1], room.height - c[1])
    for f in room.furniture:
        for p in f.parts:
            plo, phi = part_bounds(p)
            d = np.maximum(np.maximum(plo - c, 0.0), c - phi)
            best = min(best, float(np.linalg.norm(d)))
    return best


def generate_room(seed: int) -> Room:
    """The room for ``seed`` (any non-negative integer); see the module docstring."""
    if int(seed) < 0:
        raise ValueError(f"generate_room: seed must be >= 0, got {seed}")
    rng = np.random.default_rng([int(seed), _SALT])
    shell = sample_shell(rng)
    scenario = sample_scenario(rng)
    n_doors = int(rng.integers(1, 3))
    openings = place_openings(rng, shell, window_count(rng, scenario), n_doors)
    if scenario in ("sunny", "overcast", "dusk") and not openings.windows:
        scenario = "interior"
    capture = _capture(rng, shell)
    sun_dir = _sun_in_view(rng, openings.windows, capture) if scenario == "sunny" and rng.random() < 0.4 else None
    sky = sample_sky(rng, SKY_OF[scenario], sun_dir=sun_dir) if openings.windows else None
    materials = room_palette(rng)
    layout = Layout(shell, openings.keepout, capture)
    area = sum((c[2] - c[0]) * (c[3] - c[1]) for c in shell.cells)
    types = dict(ROOM_TYPES)
    if area < 9.0:
        types.update(living=0.1, kitchen=0.05)
    names_t = list(types)
    probs = np.array(list(types.values()))
    room_type = names_t[int(rng.choice(len(names_t), p=probs / probs.sum()))]
    if shell.kind == "large":
        room_type = "large"
        if rng.random() < 0.5:  # concrete, epoxy or polished stone floors of big spaces
            materials["floor"] = concrete_floor(rng, "floor")
    names = _Names()
    _PROGRAMS[room_type](rng, layout, names, shell.height)
    for _ in range(int(rng.integers(0, 4))):
        layout.hang(rng, fu.painting(rng, str(rng.choice(CANVAS_MATERIALS))))

    # Light sources.
    p_on = lights_on_probability(scenario)
    main_on = rng.random() < p_on or scenario in ("night", "interior")
    tables = [f for f in layout.furniture if f.kind == "table"]
    items, mats, lights = ceiling_lights(rng, shell.cells, shell.height, main_on, capture, tables)
    fmats, flights = fixture_materials(rng, layout.fixtures, p_on, 0.6 if main_on else 0.3)
    sitems, smats, slights = space_lights(rng, openings.spaces, 0.3 + 0.5 * p_on)
    materials.update(mats)
    materials.update(fmats)
    materials.update(smats)

    # Shell surfaces.
    accent = None
    if rng.random() < 0.2 and len(shell.walls) > 1:
        from roomlight.datagen.synth.materials import _paint

        accent = int(rng.integers(len(shell.walls)))
        materials["accent"] = _paint(rng, "accent")
    parts = []
    for i, w in enumerate(shell.walls):
        parts += wall_quads(w, shell.height, "accent" if i == accent else "wall")
    parts += floor_ceiling_quads(shell.cells, shell.height, "floor", "ceiling")
    parts += openings.parts

    for f in layout.furniture:
        f.__dict__.pop("wall", None)
        f.__dict__.pop("t", None)
    return Room(seed=int(seed), shell=shell.kind, room_type=room_type, lighting=scenario,
                height=shell.height, cells=[list(c) for c in shell.cells], capture=capture,
                yaw=float(rng.uniform(0.0, 2.0 * math.pi)), materials=materials, shell_parts=parts,
                furniture=layout.furniture + items + sitems, lights=lights + flights + slights,
                windows=openings.windows, doors=openings.doors, sky=sky)


def box_room(size=(4.0, 2.7, 5.0), capture=(1.5, 1.4, 2.0), albedo=(0.6, 0.6, 0.6), emission=None,
             yaw: float = 0.0, light: bool = True) -> Room:
    """An empty closed box room ``[0, sx] x [0, sy] x [0, sz]`` (for tests and references).

    Args:
        size: (sx, sy, sz) metres; sy is the ceiling height.
        capture: capture point inside the box.
        albedo: diffuse albedo of every surface.
        emission: radiance of every surface (e.g. (1, 1, 1) with albedo 0 for a furnace test),
            or None.
        light: add a 0.6 m ceiling panel of 2000 nits (ignored when ``emission`` is given).
    """
    from roomlight.datagen.synth.spec import Furniture, Light, Material, Quad

    sx, sy, sz = (float(v) for v in size)
    cells = [(0.0, 0.0, sx, sz)]
    mats = {"surface": Material("surface", "diffuse", albedo, emission=emission)}
    parts = []
    for w in plan_walls(cells):
        parts += wall_quads(w, sy, "surface")
    parts += floor_ceiling_quads(cells, sy, "surface", "surface")
    furniture, lights = [], []
    if emission is None and light:
        mats["panel"] = Material("panel", "black", emission=(2000.0, 2000.0, 2000.0))
        cx, cz = sx / 2, sz / 2
        furniture.append(Furniture("ceiling_panels", (cx - 0.3, sy - 0.01, cz - 0.3), (cx + 0.3, sy, cz + 0.3),
                                   [Quad((cx - 0.3, sy - 0.005, cz - 0.3), (0.6, 0, 0), (0, 0, 0.6), "panel")]))
        lights.append(Light("panel", "panel", (cx, sy, cz), math.pi * 0.36 * 2000.0))
    return Room(seed=0, shell="box", room_type="empty", lighting="interior", height=sy, cells=[list(c) for c in cells],
                capture=tuple(float(v) for v in capture), yaw=float(yaw), materials=mats, shell_parts=parts,
                furniture=furniture, lights=lights)
