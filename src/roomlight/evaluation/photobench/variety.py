"""The wide suite's draws: photographs that differ on purpose from what the room generator usually makes.

The original photo benchmark photographs the generator's own rooms with its own cameras and object
colours, so a method tuned on it may be tuned to the generator. ``roomlight bench make-photos --suite
wide`` keeps the staging and the truth of :mod:`roomlight.evaluation.photobench.builder` and changes what
is photographed, each photo by a plan drawn from (seed, index) before anything is rendered:

- **the room** (procedural photos): photo ``i`` asks for a room kind in turn, :data:`ROOM_KINDS`
  (very small, very large, sunlit through a window, several lamps lit at night, lamps and windows
  both), found among the generator's rooms by drawing seeds until one matches; then its walls are
  repainted (bright white, or dark) or its floor made dark wood, and every lamp gets its own colour
  temperature from 2200 K to 6500 K at its luminance;
- **the camera**: eye height from a table top to standing, pitch from -35 to +10 degrees (drawn for each
  staging attempt; the look-at point keeps its heading and distance), horizontal field of view from
  40 to 90 degrees (the config's ranges); whether a lamp or window shows in the frame is measured and
  recorded, not forced;
- **the objects**: albedos from 0.03 to 0.9: white, black, saturated colours and greys, metals and
  glossy plastics (roughness down to 0.05): :func:`~roomlight.evaluation.photobench.objects.draw_material`'s
  ``wide`` palette;
- **the light** (every ``captured_every``-th photo): a table and a floor lit by a real captured HDR
  panorama at infinity (:mod:`roomlight.evaluation.photobench.captured`) instead of a procedural room.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["ROOM_KINDS", "Plan", "photo_plan", "room_matches", "edit_room",
           "aim_at_pitch", "SALT_PLAN"]

#: The room kinds asked for in turn (photo i asks for ROOM_KINDS[i % len]).
ROOM_KINDS = ("small", "large", "sunlit", "lamps", "windows", "small", "large", "lamps")
#: Colour temperatures (K) the lamps of a wide-suite room are given.
LAMP_KELVIN = (2200.0, 2700.0, 3000.0, 4000.0, 5000.0, 6500.0)
SALT_PLAN = 0x706C616E
#: Floor area (m^2) under which a room is very small, and over which it is very large.
SMALL_AREA, LARGE_AREA = 9.0, 40.0


@dataclass(frozen=True)
class Plan:
    """What one photo of the wide suite is (drawn before any rendering).

    Attributes:
        light: ``room`` (a procedural room) or ``captured`` (a set under a captured HDR panorama).
        room_kind: the room kind asked for (``room`` photos), else ``""``.
        walls: ``keep``, ``white`` or ``dark``; floor: ``keep`` or ``dark-wood`` (``""`` for a captured set).
        fov: horizontal field of view (degrees).
    """

    light: str
    room_kind: str
    walls: str
    floor: str
    fov: float

    def to_dict(self) -> dict:
        return {"light": self.light, "room_kind": self.room_kind, "walls": self.walls, "floor": self.floor,
                "fov": self.fov}


def photo_plan(config, index: int) -> Plan:
    """The plan of photo ``index`` under ``config`` (a :class:`PhotoBenchConfig` of the wide suite)."""
    rng = np.random.default_rng([config.seed, index, SALT_PLAN])
    every = int(config.captured_every)
    captured = every > 0 and index % every == every - 1
    walls = ("keep", "white", "dark")[int(rng.integers(3))]
    floor = "dark-wood" if rng.random() < 0.4 else "keep"
    fov = float(rng.uniform(*config.fov_range)) if config.fov_range else float(config.fov)
    if captured:  # a set of its own: no room to ask for or repaint
        return Plan("captured", "", "", "", round(fov, 3))
    room_photos = index - (index // every if every else 0)  # the procedural photos before this one
    return Plan("room", ROOM_KINDS[room_photos % len(ROOM_KINDS)], walls, floor, round(fov, 3))


def _area(room) -> float:
    return float(sum((c[2] - c[0]) * (c[3] - c[1]) for c in room.cells))


def room_matches(room, kind: str) -> bool:
    """Whether a generated room is of the asked kind (see :data:`ROOM_KINDS`). A room with no light at all
    (no lit lamp, no window: the generator makes some among its smallest rooms) is no kind: its photo
    would be black."""
    lit = [light for light in room.lights if light.on]
    if not room.emitters() and not room.windows:
        return False
    if kind == "small":
        return _area(room) < SMALL_AREA
    if kind == "large":
        return _area(room) > LARGE_AREA or room.shell == "large"
    if kind == "sunlit":
        return room.lighting == "sunny" and bool(room.windows)
    if kind == "lamps":
        return room.lighting in ("night", "dusk", "interior") and len(lit) >= 2
    if kind == "windows":
        return bool(lit) and bool(room.windows)
    return True


def edit_room(room, plan: Plan, rng: np.random.Generator) -> dict:
    """Repaint the room's walls / floor and recolour its lamps as the plan says; returns what changed."""
    from roomlight.core.color import luminance_np
    from roomlight.datagen.synth.color import hsv_albedo, light_rgb
    from roomlight.datagen.synth.spec import Material

    changed: dict = {}
    m = room.materials
    if plan.walls != "keep":
        value = float(rng.uniform(0.9, 0.96)) if plan.walls == "white" else float(rng.uniform(0.2, 0.35))
        albedo = hsv_albedo(float(rng.random()), float(rng.uniform(0.0, 0.05 if plan.walls == "white" else 0.3)), value)
        for name in ("wall", "adj_wall"):
            if name in m:
                m[name] = Material(name, "diffuse", albedo)
        changed["wall_albedo"] = [round(float(a), 4) for a in albedo]
    if plan.floor == "dark-wood":
        albedo = hsv_albedo(float(rng.uniform(0.04, 0.08)), float(rng.uniform(0.5, 0.8)), float(rng.uniform(0.18, 0.3)))
        old = m.get("floor")
        texture = old.texture if old is not None and old.texture and old.texture.get("pattern") == "wood" else None
        m["floor"] = Material("floor", "plastic", albedo, float(rng.uniform(0.05, 0.2)), texture)
        changed["floor_albedo"] = [round(float(a), 4) for a in albedo]
    kelvins = {}
    for light in room.lights:
        mat = m.get(light.material)
        if mat is None or mat.emission is None or light.material in kelvins:
            continue
        nits = float(luminance_np(np.asarray(mat.emission, np.float64)))
        k = float(LAMP_KELVIN[int(rng.integers(len(LAMP_KELVIN)))])
        mat.emission = tuple(float(v) for v in light_rgb(k, nits))
        kelvins[light.material] = k
    if kelvins:
        changed["lamp_kelvin"] = kelvins
    return changed


def aim_at_pitch(eye: np.ndarray, target: np.ndarray, pitch_deg: float) -> np.ndarray:
    """``target`` moved along its vertical so that the camera at ``eye`` looks at it with pitch
    ``pitch_deg`` (negative: down), keeping its heading and horizontal distance."""
    d = np.asarray(target, np.float64) - eye
    out = np.asarray(target, np.float64).copy()
    out[1] = eye[1] + float(np.hypot(d[0], d[2])) * math.tan(math.radians(pitch_deg))
    return out
