"""Photographs lit by real captured light: a table and a floor under an HDR panorama at infinity.

Every procedural room's light comes from the generator (its lamps, its sky model). A third of the
wide suite's photographs are lit instead by real HDR captures: the CC0 panoramas that ship in Blender's
data files (``datafiles/studiolights/world/*.exr`` of the ``bpy`` wheel that ``make blender``
installs: city, courtyard, forest, interior, night, studio, sunrise, sunset), placed as distant light
(Mitsuba ``envmap``, turned about the vertical by a drawn angle) around a local set that the path tracer
lights and shadows: a floor, a table block and, half the time, a wall panel behind the table. The
staging, the truth and the scoring are the procedural photos' own; only the set differs.

Those panoramas are for evaluation only: nothing in roomlight trains on them (they are not in any data
folder the project writes), and docs/benchmark.md lists which photos use which.

Rays that leave the set (towards the captured sky) have no depth; the photo's depth and the oracle
light's give them :data:`FAR_DEPTH`, far enough that a light there acts as one at infinity for objects
within a few metres.
"""

from __future__ import annotations

import glob
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from roomlight.errors import RoomlightError
from roomlight.evaluation.photobench.roomscene import SceneSet

__all__ = ["FAR_DEPTH", "ENV_LIGHTS", "CapturedSet", "CapturedRoom", "find_captured_lights"]

#: Depth (metres) given to rays that leave a captured-light set.
FAR_DEPTH = 30.0
#: Environment variable naming the folder of captured panoramas (overrides the search).
ENV_LIGHTS = "ROOMLIGHT_CAPTURED_LIGHTS"


def find_captured_lights(folder=None) -> list[Path]:
    """The captured panoramas (``*.exr``, sorted by name): in ``folder``, else ``$ROOMLIGHT_CAPTURED_LIGHTS``,
    else Blender's studio lights in ``.venv-blender`` beside the working directory or the package's
    checkout; a one-line error saying how to get them otherwise."""
    folder = folder or os.environ.get(ENV_LIGHTS)
    if folder:
        found = sorted(Path(folder).glob("*.exr"))
        if not found:
            raise RoomlightError(f"captured lights: no .exr panorama in {folder}")
        return found
    roots = {Path.cwd(), Path(__file__).resolve().parents[4]}
    for root in sorted(roots):
        pattern = str(root / ".venv-blender" / "lib" / "python*" / "site-packages" / "bpy" / "*" / "datafiles" /
                      "studiolights" / "world" / "*.exr")
        found = sorted(Path(p) for p in glob.glob(pattern))
        if found:
            return found
    raise RoomlightError("the wide suite's captured-light photos need HDR panoramas: run `make blender` (Blender's "
                         f"CC0 studio lights), or pass --captured-lights DIR / set ${ENV_LIGHTS}")


@dataclass
class CapturedRoom:
    """What the staging and the photo record read of a room, for a captured-light set."""

    seed: int
    lighting: str                     #: the captured panorama's name
    capture: tuple                    #: where the camera stands before its eye height is drawn
    height: float = 3.0               #: a ceiling height for the eye's clamp (the set has none)
    room_type: str = "captured"
    shell: str = "open"
    cells: list = field(default_factory=list)
    lights: list = field(default_factory=list)
    windows: list = field(default_factory=list)
    env_yaw_deg: float = 0.0
    env_scale: float = 1.0
    parts: dict = field(default_factory=dict)

    def summary(self) -> dict:
        return {"light": self.lighting, "env_yaw_deg": self.env_yaw_deg, "env_scale": self.env_scale, **self.parts}


def _box(name: str, centre, size, albedo, roughness: float):
    from roomlight.core.render.mesh import mitsuba_mesh
    from roomlight.evaluation.photobench.objects import box_mesh

    v, f = box_mesh()
    v = v * np.asarray(size, np.float64) + np.asarray(centre, np.float64)
    bsdf = {"type": "principled", "base_color": {"type": "rgb", "value": [float(a) for a in albedo]},
            "roughness": float(roughness), "metallic": 0.0}
    return mitsuba_mesh(name, v, f, bsdf)


class CapturedSet(SceneSet):
    """A table set under a captured panorama, loaded as :class:`~roomlight.evaluation.photobench.roomscene.RoomScenes`
    loads a room (``room``, ``entries``, ``base``, ``scene(extra)``).

    Args:
        panorama: the captured HDR panorama (.exr); seed: draws the set (sizes, albedos, the panorama's turn).
        max_depth: longest light path of the ``path`` integrator.
    """

    def __init__(self, panorama: Path, seed: int, max_depth: int = 5):
        from roomlight.core.render.variant import mitsuba

        mi = mitsuba()
        rng = np.random.default_rng([int(seed), 0x63617074])
        yaw = float(rng.uniform(0.0, 360.0))
        floor_albedo = [float(a) for a in np.full(3, rng.uniform(0.08, 0.5)) * rng.uniform(0.85, 1.15, 3)]
        table_albedo = [float(a) for a in np.full(3, rng.uniform(0.05, 0.85)) * rng.uniform(0.85, 1.15, 3)]
        table = (float(rng.uniform(1.2, 2.0)), float(rng.uniform(0.7, 0.78)), float(rng.uniform(0.7, 1.0)))
        wall = bool(rng.random() < 0.5)
        self.entries: dict = {"type": "scene", "integrator": {"type": "path", "max_depth": int(max_depth),
                                                               "rr_depth": int(max_depth)}}
        self.entries["env"] = mi.load_dict({"type": "envmap", "filename": str(panorama), "scale": 1.0,
                                            "to_world": mi.ScalarTransform4f().rotate([0, 1, 0], yaw)})
        # the floor: a thin slab 12 m across, its top at y = 0
        self.entries["set_floor"] = _box("set_floor", (0.0, -0.05, 0.0), (12.0, 0.1, 12.0), floor_albedo, 0.7)
        self.entries["set_table"] = _box("set_table", (0.0, table[1] / 2, -2.0), table, table_albedo,
                                         float(rng.uniform(0.2, 0.7)))
        parts = {"floor_albedo": floor_albedo, "table_albedo": table_albedo, "table_size": list(table), "wall": wall}
        if wall:
            wall_albedo = [float(a) for a in np.full(3, rng.uniform(0.2, 0.9))]
            self.entries["set_wall"] = _box("set_wall", (0.0, 1.25, -3.2), (4.0, 2.5, 0.1), wall_albedo, 0.9)
            parts["wall_albedo"] = wall_albedo
        self.room = CapturedRoom(int(seed), panorama.stem, (0.0, 1.2, 0.6), env_yaw_deg=round(yaw, 4), parts=parts)
        self.base = self.scene()
