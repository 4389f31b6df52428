"""Procedural rooms, the generator: layouts, capture points, light sources, descriptions, meshes."""

import numpy as np
import pytest

pytestmark = pytest.mark.mitsuba


def test_capture_point_is_at_eye_height_and_clear_of_surfaces():
    from roomlight.datagen.synth.rooms import capture_clearance, generate_room

    for seed in range(40):
        room = generate_room(seed)
        assert 0.9 <= room.capture[1] <= 1.8
        if room.shell == "large":
            assert 3.5 <= room.height <= 8.0
        else:
            assert 2.3 <= room.height <= 4.0
        assert capture_clearance(room) >= 0.4, seed


@pytest.mark.slow
def test_generator_covers_large_spaces_and_light_colours():
    """Large spaces (halls, warehouses: >= 9 m sides, 3.5-8 m ceilings) make up ~15 % of rooms,
    and artificial light colours spread over 2700-6500 K rather than a few fixed values."""
    from roomlight.datagen.synth.color import light_rgb
    from roomlight.datagen.synth.rooms import generate_room

    rooms = [generate_room(seed) for seed in range(200)]
    large = [r for r in rooms if r.shell == "large"]
    assert 0.08 <= len(large) / len(rooms) <= 0.25
    for r in large:
        x0, z0, x1, z1 = r.cells[0]
        assert min(x1 - x0, z1 - z0) >= 9.0 and r.room_type == "large"
    assert max(r.height for r in large) > 6.0
    # Blue/red ratio of the ceiling lights: 2700 K and 6500 K bound it; many distinct values.
    lo, hi = (light_rgb(k, 1.0)[2] / light_rgb(k, 1.0)[0] for k in (2700, 6500))
    ratios = set()
    for r in rooms:
        for name in ("panel", "downlight", "fixture"):
            m = r.materials.get(name)
            if m is not None and m.emission is not None and max(m.emission) > 0:
                ratios.add(round(m.emission[2] / m.emission[0], 4))
    assert len(ratios) > 30
    assert min(ratios) >= lo - 1e-6 and max(ratios) <= hi + 1e-6
    assert min(ratios) < lo + 0.1 * (hi - lo) and max(ratios) > hi - 0.1 * (hi - lo)


@pytest.mark.slow
def test_every_generated_room_has_a_lit_source_and_a_clear_capture_point():
    """Structural checks over many seeds (no rendering): a daylight window or a switched-on
    ceiling light in the main room, capture >= 0.4 m from every surface, distinct rooms."""
    import json

    from roomlight.datagen.synth.rooms import capture_clearance, generate_room

    seen = set()
    for seed in range(150):
        room = generate_room(seed)
        daylight = bool(room.windows) and room.sky.kind in ("clear", "overcast", "dusk")
        ceiling_on = any(lt.on and lt.kind in ("panel", "downlight", "central", "pendants", "highbay") for lt in room.lights)
        assert daylight or ceiling_on, seed
        assert capture_clearance(room) >= 0.4, seed
        seen.add(json.dumps(room.to_dict(full=False), sort_keys=True))
    assert len(seen) == 150


def test_room_description_round_trips_through_json():
    import json

    from roomlight.datagen.synth.rooms import generate_room
    from roomlight.datagen.synth.spec import Room

    room = generate_room(3)
    d = json.loads(json.dumps(room.to_dict(full=True)))
    assert json.loads(json.dumps(Room.from_dict(d).to_dict(full=True))) == d


def test_mesh_primitives_are_closed_and_face_outwards():
    from roomlight.datagen.synth.mesh import MeshBuilder

    def volume(b):
        m = b.build()
        p = m.positions.astype(np.float64)[m.faces.astype(np.int64)]
        return float(np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2])).sum() / 6.0)

    b = MeshBuilder()
    b.box((0.1, 0.2, 0.3), (1.1, 0.7, 0.55))
    assert volume(b) == pytest.approx(1.0 * 0.5 * 0.25, rel=1e-6)
    b = MeshBuilder(segments=64)
    b.cylinder((0.3, 0.0, 0.2), 0.5, 2.0)
    assert volume(b) == pytest.approx(np.pi * 0.25 * 2.0, rel=0.01)
    b = MeshBuilder(segments=64)
    b.sphere((0.0, 1.0, 0.0), 0.5)
    assert volume(b) == pytest.approx(4 / 3 * np.pi * 0.125, rel=0.01)
