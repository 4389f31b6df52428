"""Light sources: lighting scenarios, ceiling lights, lamps, screens and adjacent-space lights.

Artificial lights are specified by their luminous flux (lumens) and colour temperature; the
emitted radiance of a Lambertian emitter of area A is L = flux / (pi A) (nits). Ranges:
LED panels 2-5 klm per m^2 of panel (L ~ 1-3 knits), downlights 400-1200 lm on a 4-8 cm
radius (L ~ 20-100 knits), ceiling fixtures 1.5-4 klm, pendants and lamps 300-1500 lm through
a shade, screens 80-400 nits. Daylight comes from window portals (:mod:`roomlight.datagen.synth.sky`).

Scenarios (probability): ``sunny`` 0.3 (clear sky, sun), ``overcast`` 0.2, ``dusk`` 0.15
(dim sky, lights on), ``night`` 0.2 (dark windows, lights on), ``interior`` 0.15 (no
windows). The generator guarantees that the main room has at least one lit source: a
daylight window or switched-on ceiling lights.
"""

from __future__ import annotations

import math

import numpy as np

from roomlight.datagen.synth.color import light_rgb
from roomlight.datagen.synth.furniture import Fixture
from roomlight.datagen.synth.spec import Cylinder, Disk, Furniture, Light, Material, Quad

__all__ = [
    "SCENARIOS",
    "ceiling_lights",
    "fixture_materials",
    "lights_on_probability",
    "sample_scenario",
    "space_lights",
    "window_count",
]

SCENARIOS = {"sunny": 0.3, "overcast": 0.2, "dusk": 0.15, "night": 0.2, "interior": 0.15}
SKY_OF = {"sunny": "clear", "overcast": "overcast", "dusk": "dusk", "night": "night", "interior": None}


def sample_scenario(rng) -> str:
    names = list(SCENARIOS)
    return str(names[int(rng.choice(len(names), p=np.array(list(SCENARIOS.values()))))])


def window_count(rng, scenario: str) -> int:
    return {"sunny": int(rng.integers(1, 5)), "overcast": int(rng.integers(1, 5)), "dusk": int(rng.integers(1, 4)),
            "night": int(rng.integers(0, 4)), "interior": 0}[scenario]


def lights_on_probability(scenario: str) -> float:
    return {"sunny": 0.15, "overcast": 0.4, "dusk": 0.9, "night": 1.0, "interior": 1.0}[scenario]


def _emissive(name: str, flux: float, area: float, kelvin: float) -> Material:
    return Material(name, "black", (0.0, 0.0, 0.0), emission=light_rgb(kelvin, flux / (math.pi * area)))


def _off(name: str, albedo=(0.75, 0.75, 0.72)) -> Material:
    return Material(name, "diffuse", albedo)


def _grid(c, spacing: float):
    x0, z0, x1, z1 = c
    nx = max(1, round((x1 - x0) / spacing))
    nz = max(1, round((z1 - z0) / spacing))
    xs = x0 + (np.arange(nx) + 0.5) * (x1 - x0) / nx
    zs = z0 + (np.arange(nz) + 0.5) * (z1 - z0) / nz
    return [(float(x), float(z)) for x in xs for z in zs]


def ceiling_lights(rng, cells, height: float, on: bool, capture, tables=()) -> tuple[list, dict, list]:
    """Ceiling lights for the given cells: (furniture, materials, lights).

    Style: LED panels, downlights, one fixture per cell, or pendants (over ``tables`` —
    Furniture — when there are any). Pendants keep >= 0.5 m horizontally from ``capture``
    or hang >= 0.4 m above it.
    """
    # Tall spaces (halls, warehouses) use fewer, stronger fixtures; ``tall`` scales spacing and
    # flux so the illuminance on the floor stays in the range of ordinary rooms (flux ~ distance^2).
    tall = max(1.0, height / 2.8)
    if tall > 1.3:
        style = str(rng.choice(["panels", "downlights", "highbay"], p=[0.3, 0.2, 0.5]))
    else:
        style = str(rng.choice(["panels", "downlights", "central", "pendants"], p=[0.3, 0.35, 0.2, 0.15]))
    # White LEDs and lamps span warm (2700 K) to daylight (6500 K); warm tones are the most common.
    kelvin = float(rng.uniform(2700, 3500) if rng.random() < 0.5 else rng.uniform(3500, 6500))
    items, mats, lights = [], {}, []
    if style == "highbay":
        return _highbay(rng, cells, height, on, capture, kelvin)
    if style == "panels":
        pw, pd = [(0.6, 0.6), (1.2, 0.3), (1.2, 0.6)][int(rng.integers(3))]
        spacing = float(rng.uniform(1.8, 3.0)) * tall
        lum = float(rng.uniform(1000, 3000))
        parts, area = [], 0.0
        for c in cells:
            for x, z in _grid(c, spacing):
                if x - pw / 2 < c[0] or x + pw / 2 > c[2] or z - pd / 2 < c[1] or z + pd / 2 > c[3]:
                    continue
                parts.append(Quad((x - pw / 2, height - 0.005, z - pd / 2), (pw, 0, 0), (0, 0, pd), "panel"))
                area += pw * pd
        if parts:
            items.append(Furniture("ceiling_panels", (0, height - 0.01, 0), (0, height, 0), parts))
            mats["panel"] = (Material("panel", "black", emission=light_rgb(kelvin, lum)) if on
                             else _off("panel", (0.8, 0.8, 0.8)))
            lights.append(Light("panel", "panel", (0.0, height, 0.0), math.pi * area * lum if on else 0.0, on))
    elif style == "downlights":
        r = float(rng.uniform(0.04, 0.08)) * math.sqrt(tall)
        spacing = float(rng.uniform(1.0, 2.0)) * tall
        flux = float(rng.uniform(400, 1200)) * tall * tall
        parts = []
        for c in cells:
            for x, z in _grid(c, spacing):
                parts.append(Disk((x, height - 0.003, z), r, "downlight", -1.0))
                parts.append(Disk((x, height - 0.002, z), r + 0.015, "white", -1.0))
        items.append(Furniture("downlights", (0, height - 0.01, 0), (0, height, 0), parts))
        mats["downlight"] = _emissive("downlight", flux, math.pi * r * r, kelvin) if on else _off("downlight")
        lights.append(Light("downlight", "downlight", (0.0, height, 0.0), flux * len(parts) / 2 if on else 0.0, on))
    else:
        spots = []
        if style == "pendants" and tables:
            for t in tables:
                cx, cz = 0.5 * (t.lo[0] + t.hi[0]), 0.5 * (t.lo[2] + t.hi[2])
                spots.append((cx, cz, t.hi[1] + float(rng.uniform(0.65, 0.9))))
        else:
            for c in cells:
                spots.append((0.5 * (c[0] + c[2]), 0.5 * (c[1] + c[3]), None))
        r = float(rng.uniform(0.12, 0.3))
        h = float(rng.uniform(0.08, 0.25))
        flux = float(rng.uniform(600, 1500) if style == "pendants" else rng.uniform(1500, 4000))
        parts, area = [], 0.0
        for x, z, bottom in spots:
            if bottom is None:
                bottom = height - h if style == "central" else height - float(rng.uniform(0.5, 0.9))
            far = math.hypot(x - capture[0], z - capture[2]) > r + 0.5
            if not far and bottom < capture[1] + 0.4 + h:
                bottom = height - h  # lift it to the ceiling rather than hang it at the capture point
            bottom = min(bottom, height - h)
            if bottom + h < height - 0.01:
                parts.append(Cylinder((x, bottom + h, z), 0.006, height - bottom - h, "black", "none"))
            parts.append(Cylinder((x, bottom, z), r, h, "fixture", "bottom" if bottom + h >= height - 1e-6 else "both"))
            area += 2 * math.pi * r * h + math.pi * r * r
        items.append(Furniture("pendants" if style == "pendants" else "ceiling_fixture",
                               (0, height - 1, 0), (0, height, 0), parts))
        per = area / max(1, len(spots))
        mats["fixture"] = _emissive("fixture", flux, per, kelvin) if on else _off("fixture")
        lights.append(Light(style, "fixture", (0.0, height, 0.0), flux * len(spots) if on else 0.0, on))
    return items, mats, lights


def _highbay(rng, cells, height: float, on: bool, capture, kelvin: float) -> tuple[list, dict, list]:
    """High-bay pendants of a large space: a grid (4-9 m) of wide cylinders hung 0.3-1.5 m below
    the ceiling, 6-25 klm each, kept >= 1 m horizontally from the capture point."""
    r = float(rng.uniform(0.2, 0.35))
    h = float(rng.uniform(0.1, 0.25))
    drop = float(rng.uniform(0.3, 1.5))
    spacing = float(rng.uniform(4.0, 9.0))
    flux = float(rng.uniform(6000, 25000))
    parts, n = [], 0
    bottom = height - drop - h
    for c in cells:
        for x, z in _grid(c, spacing):
            if math.hypot(x - capture[0], z - capture[2]) < r + 1.0:
                continue
            parts.append(Cylinder((x, bottom + h, z), 0.01, height - bottom - h, "black", "none"))
            parts.append(Cylinder((x, bottom, z), r, h, "fixture", "both"))
            n += 1
    area = 2 * math.pi * r * h + 2 * math.pi * r * r
    mats = {"fixture": _emissive("fixture", flux, area, kelvin) if on else _off("fixture")}
    items = [Furniture("highbay", (0, bottom, 0), (0, height, 0), parts)] if parts else []
    lights = [Light("highbay", "fixture", (0.0, height, 0.0), flux * n if on else 0.0, on)] if parts else []
    return items, mats if parts else {}, lights


def fixture_materials(rng, fixtures: list[Fixture], p_lamp_on: float, p_screen_on: float) -> tuple[dict, list]:
    """Materials and :class:`Light` records for lamp shades and screens placed with furniture."""
    mats, lights = {}, []
    for fx in fixtures:
        if fx.material in mats:
            continue
        if fx.kind == "lamp":
            on = rng.random() < p_lamp_on
            flux = float(rng.uniform(300, 1200))
            kelvin = float(rng.uniform(2400, 3500) if rng.random() < 0.75 else rng.uniform(3500, 6500))
            mats[fx.material] = (_emissive(fx.material, flux, fx.area, kelvin) if on
                                 else _off(fx.material, tuple(float(v) for v in rng.uniform(0.4, 0.85, 3))))
            lights.append(Light("lamp", fx.material, fx.center, flux if on else 0.0, on))
        else:
            on = rng.random() < p_screen_on
            lum = float(rng.uniform(80, 400))
            mats[fx.material] = (Material(fx.material, "black", emission=light_rgb(float(rng.uniform(6000, 9000)), lum),
                                          emission_texture={"pattern": "screen", "seed": int(rng.integers(2**31 - 1))})
                                 if on else Material(fx.material, "plastic", (0.01, 0.01, 0.01), 0.05))
            lights.append(Light("screen", fx.material, fx.center, math.pi * fx.area * lum if on else 0.0, on))
    return mats, lights


def space_lights(rng, spaces: list, p_on: float) -> tuple[list, dict, list]:
    """One ceiling panel per adjacent space, on with probability ``p_on``."""
    items, mats, lights = [], {}, []
    for k, (x0, z0, x1, z1, h) in enumerate(spaces):
        on = rng.random() < p_on
        name = f"space_light_{k}"
        cx, cz = 0.5 * (x0 + x1), 0.5 * (z0 + z1)
        s = float(min(0.6, 0.5 * (x1 - x0), 0.5 * (z1 - z0)))
        items.append(Furniture("space_light", (cx - s / 2, h - 0.01, cz - s / 2), (cx + s / 2, h, cz + s / 2),
                               [Quad((cx - s / 2, h - 0.005, cz - s / 2), (s, 0, 0), (0, 0, s), name)]))
        flux = float(rng.uniform(500, 2000))
        mats[name] = _emissive(name, flux, s * s, float(rng.uniform(2700, 5000))) if on else _off(name)
        lights.append(Light("space", name, (cx, h, cz), flux if on else 0.0, on))
    return items, mats, lights
