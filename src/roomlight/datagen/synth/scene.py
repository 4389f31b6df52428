"""Room description -> Mitsuba scene.

Primitives are triangulated per material into one ``mi.Mesh`` each (few shapes, world-space
texture coordinates scaled by the material's tile size). Emissive materials become Mitsuba
``area`` emitters; every window gets a portal mesh with a
:mod:`roomlight.datagen.synth.portal` emitter. Emitters are sampled in proportion to their
estimated flux (``sampling_weight``), so a 100 klx sun patch does not starve a desk lamp
of samples, nor the reverse.
"""

from __future__ import annotations

import math

from roomlight.core.color import luminance_np
from roomlight.core.render.mesh import mitsuba_mesh
from roomlight.core.render.variant import mitsuba
from roomlight.datagen.synth.color import luminance
from roomlight.datagen.synth.materials import bsdf_dict, emission_texture
from roomlight.datagen.synth.mesh import MeshArrays, MeshBuilder
from roomlight.datagen.synth.portal import portal_emitter, portal_power, portal_quad
from roomlight.datagen.synth.spec import Room

__all__ = ["DEFAULT_MAX_DEPTH", "build_scene", "room_meshes", "scene_entries"]

#: Path length limit (Mitsuba's ``max_depth``: 1 = emitters seen directly, 2 = direct
#: lighting, 5 = three indirect bounces).
DEFAULT_MAX_DEPTH = 5


def room_meshes(room: Room) -> dict[str, MeshArrays]:
    """Triangle meshes of the room, one per material name (emissive ones included)."""
    builders: dict[str, MeshBuilder] = {}
    for part in room.all_parts():
        if part.material not in room.materials:
            raise KeyError(f"room {room.seed}: part uses unknown material {part.material!r}")
        if part.material not in builders:
            m = room.materials[part.material]
            tile = float(m.texture.get("tile", 1.0)) if m.texture else 1.0
            builders[part.material] = MeshBuilder(tile=tile)
        builders[part.material].add(part)
    return {name: b.build() for name, b in builders.items()}


def _mesh(name: str, arrays: MeshArrays, bsdf, emitter=None):
    return mitsuba_mesh(name, arrays.positions, arrays.faces, bsdf, normals=arrays.normals, uvs=arrays.uvs,
                        emitter=emitter)


def _mean_emission(m) -> float:
    lum = luminance(m.emission)
    if m.emission_texture:
        from roomlight.datagen.synth.textures import make_texture

        tex = make_texture(m.emission_texture)
        lum *= float(luminance_np(tex).mean())
    return lum


def scene_entries(room: Room, max_depth: int = DEFAULT_MAX_DEPTH, rr_depth: int | None = None,
                  integrator: dict | None = None) -> dict:
    """The room's ``mi.load_dict`` entries: the integrator and its instantiated meshes and emitters.

    The entries can be loaded more than once, with other entries added (objects placed in the
    room), without triangulating and texturing the room again: ``mi.load_dict({**entries, **more})``.
    Arguments as :func:`build_scene`.
    """
    mi = mitsuba()
    meshes = room_meshes(room)
    black = mi.load_dict({"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.0, 0.0, 0.0]}})
    powers: dict[str, float] = {}
    for name, arrays in meshes.items():
        m = room.materials[name]
        if m.emission is not None and max(m.emission) > 0:
            powers[name] = math.pi * arrays.area * _mean_emission(m)
    for k, w in enumerate(room.windows):
        sky_flux, sun_flux = portal_power(w, room.sky)
        powers[f"portal_{k}"] = sky_flux + sun_flux
    floor = 0.01 * max(powers.values()) if powers else 0.0

    entries: dict = {"type": "scene"}
    if integrator is None:
        integrator = {"type": "path", "max_depth": int(max_depth),
                      "rr_depth": int(rr_depth if rr_depth is not None else max_depth)}
    entries["integrator"] = integrator
    for name, arrays in meshes.items():
        m = room.materials[name]
        emitter = None
        if name in powers:
            emitter = mi.load_dict({"type": "area", "radiance": emission_texture(mi, m),
                                    "sampling_weight": float(powers[name] + floor)})
        bsdf = black if m.emission is not None else mi.load_dict(bsdf_dict(mi, m))
        entries[f"mesh_{name}"] = _mesh(name, arrays, bsdf, emitter)
    for k, w in enumerate(room.windows):
        o, a, b = portal_quad(w)
        builder = MeshBuilder()
        builder.quad(o, a, b, "local")
        emitter = portal_emitter(mi, w, room.sky, powers[f"portal_{k}"] + floor)
        entries[f"portal_{k}"] = _mesh(f"portal_{k}", builder.build(), black, emitter)
    return entries


def build_scene(room: Room, max_depth: int = DEFAULT_MAX_DEPTH, rr_depth: int | None = None,
                integrator: dict | None = None, extra: dict | None = None):
    """Instantiate the room as a ``mi.Scene`` with a ``path`` integrator.

    Args:
        room: the room description.
        max_depth: Mitsuba path length limit (see :data:`DEFAULT_MAX_DEPTH`).
        rr_depth: depth at which Russian roulette starts (default: ``max_depth``, i.e. none).
        integrator: a full integrator dict overriding the two settings above.
        extra: more scene entries by id (Mitsuba dicts or objects: probe spheres, a sensor) placed
            in the room as they are; an id the room uses itself is refused.
    Returns:
        ``mi.Scene`` (no sensor: render it with :mod:`roomlight.datagen.synth.camera`).
    """
    entries = scene_entries(room, max_depth, rr_depth, integrator)
    for key, value in (extra or {}).items():
        if key in entries:
            raise KeyError(f"room {room.seed}: extra scene entry {key!r} clashes with the room's own")
        entries[key] = value
    return mitsuba().load_dict(entries)
