"""The wide photo suite: what each photo was asked to be is what was built."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from roomlight.errors import RoomlightError
from roomlight.evaluation.photobench.config import PhotoBenchConfig, suite_config
from roomlight.evaluation.photobench.objects import draw_material
from roomlight.evaluation.photobench.variety import ROOM_KINDS, aim_at_pitch, photo_plan


# ------------------------------------------------------------------------------ no Mitsuba
def test_the_original_suite_s_settings_are_unchanged_so_its_built_photos_still_match():
    keys = set(PhotoBenchConfig().scene_settings())
    assert not keys & {"suite", "fov_range", "pitch_range", "captured_every"}
    assert suite_config("rooms") == PhotoBenchConfig()
    wide = suite_config("wide", n=24)
    assert wide.scene_settings()["suite"] == "wide" and wide.n == 24
    with pytest.raises(RoomlightError, match="--suite must be one of rooms, wide"):
        suite_config("tiny")


def test_plans_cover_every_room_kind_and_every_third_photo_is_captured():
    cfg = suite_config("wide", n=24)
    plans = [photo_plan(cfg, i) for i in range(24)]
    assert [p.light for p in plans] == ["room", "room", "captured"] * 8
    rooms = [p.room_kind for p in plans if p.light == "room"]
    assert rooms == [ROOM_KINDS[k % len(ROOM_KINDS)] for k in range(16)]  # each kind in turn, none skipped
    assert all(40.0 <= p.fov <= 90.0 for p in plans)
    assert photo_plan(cfg, 5) == photo_plan(suite_config("wide", n=3), 5)  # fixed by (seed, index) alone


def test_the_wide_palette_spans_black_to_white_and_saturated_colours():
    rng = np.random.default_rng(3)
    mats = [draw_material(rng, 0.3, (0.05, 0.8), "wide") for _ in range(4000)]
    a = np.array([m.albedo for m in mats])
    assert a.min() >= 0.03 and a.max() <= 0.9
    grey = np.ptp(a, axis=1) < 1e-12
    lum = a.mean(1)
    assert 0.2 < np.mean(grey & (lum >= 0.85)) < 0.3      # white, a quarter
    assert 0.2 < np.mean(grey & (lum <= 0.05)) < 0.32     # black, a quarter (and the darkest greys)
    saturated = (a.max(1) - a.min(1)) / a.max(1) > 0.8
    assert 0.2 < np.mean(saturated) < 0.3
    assert 0.25 < np.mean([m.metallic == 1.0 for m in mats]) < 0.35
    assert min(m.roughness for m in mats) < 0.06


def test_real_metal_colours_give_every_metal_a_real_metal_s_reflectance_and_change_nothing_else():
    from roomlight.evaluation.photobench.objects import REAL_METALS

    a, b = np.random.default_rng(5), np.random.default_rng(5)
    drawn = [draw_material(a, 0.3, (0.05, 0.8), "wide") for _ in range(400)]
    real = [draw_material(b, 0.3, (0.05, 0.8), "wide", "real") for _ in range(400)]
    first = next(k for k, m in enumerate(drawn) if m.metallic)
    assert drawn[:first] == real[:first]          # the same draws up to the first metal
    assert (real[first].roughness, real[first].metallic) == (drawn[first].roughness, 1.0)
    metals = [m for m in real if m.metallic]
    assert len(metals) > 80 and all(m.albedo in REAL_METALS.values() for m in metals)
    assert len({m.albedo for m in metals}) == len(REAL_METALS)   # every metal of the table drawn
    # none darker than about half the light, none of the suite's dark "metals"
    assert min(np.mean(m.albedo) for m in metals) > 0.45
    assert sum(np.mean(m.albedo) < 0.45 for m in drawn if m.metallic) > 40
    # the setting reaches the suite's scene settings only when it is not the default
    assert "metal_colours" not in suite_config("wide").scene_settings()
    assert suite_config("wide", metal_colours="real").scene_settings()["metal_colours"] == "real"
    with pytest.raises(RoomlightError, match="metal_colours must be one of as-drawn, real"):
        suite_config("wide", metal_colours="shiny")


def test_a_room_without_any_light_is_no_kind_of_room():
    """Seed 700201908's room is small and has neither a lamp nor a window: the wide suite must not
    photograph it (it did once, and the photo was black)."""
    from roomlight.datagen.synth.rooms import generate_room
    from roomlight.evaluation.photobench.variety import room_matches

    dark = generate_room(700201908)
    assert not dark.emitters() and not dark.windows and dark.lighting == "interior"
    assert not any(room_matches(dark, kind) for kind in set(ROOM_KINDS))


def test_aiming_at_a_pitch_keeps_heading_and_distance():
    eye, target = np.array([0.0, 1.0, 0.0]), np.array([3.0, 0.2, -4.0])
    for pitch in (-35.0, 0.0, 10.0):
        t = aim_at_pitch(eye, target, pitch)
        d = t - eye
        assert math.degrees(math.atan2(d[1], math.hypot(d[0], d[2]))) == pytest.approx(pitch)
        assert (t[0], t[2]) == (target[0], target[2])


def test_missing_captured_lights_get_one_line(tmp_path, monkeypatch):
    from roomlight.evaluation.photobench.captured import find_captured_lights

    with pytest.raises(RoomlightError, match="no .exr panorama in"):
        find_captured_lights(tmp_path)


# ------------------------------------------------------------------------------ a built wide suite
def _captured_panorama(folder):
    """A captured-looking HDR sky: a dim blue dome, a bright sun and a brown ground (no Blender needed)."""
    from roomlight.core.io import write_exr

    h, w = 32, 64
    theta = (np.arange(h) + 0.5) / h * math.pi
    rgb = np.zeros((h, w, 3), np.float32)
    rgb[theta < math.pi / 2] = (0.3, 0.45, 0.8)
    rgb[theta >= math.pi / 2] = (0.25, 0.18, 0.1)
    rgb[4:7, 20:24] = 800.0
    folder.mkdir()
    write_exr(folder / "sky.exr", {c: rgb[..., i] for i, c in enumerate("RGB")}, half=False)
    return folder


@pytest.mark.mitsuba
@pytest.mark.slow
def test_a_wide_build_is_what_its_plans_ask_for(tmp_path):
    from roomlight.datagen.synth.rooms import generate_room
    from roomlight.evaluation.photobench.builder import make_photo_benchmark
    from roomlight.evaluation.photobench.captured import FAR_DEPTH
    from roomlight.evaluation.photobench.builder import photo_seeds, room_of_record
    from roomlight.evaluation.photobench.case import read_depth_exr, read_rgb_exr
    from roomlight.evaluation.photobench.roomscene import RoomScenes
    from roomlight.evaluation.photobench.scoring import load_truth
    from roomlight.evaluation.photobench.tracing import trace_image

    lights = _captured_panorama(tmp_path / "lights")
    cfg = suite_config("wide", n=3, width=128, height=96, spp=8, probe_spp=16, oracle_height=16, oracle_spp=8,
                       insert_spp=32, probes=2)   # a small clean insertion truth: its size is not what is tested
    result = make_photo_benchmark(tmp_path / "wide", cfg, progress=False, captured_lights=lights)
    assert not result["failed"], result["failed"]
    for i in range(3):
        photo = tmp_path / "wide" / f"photo-{i:05d}"
        rec = json.loads((photo / "truth" / "photo.json").read_text())
        plan = photo_plan(cfg, i)
        assert rec["plan"] == plan.to_dict()
        cam = rec["camera"]
        # the horizontal field of view from the focal length, worked by hand
        assert math.degrees(2 * math.atan(cam["width"] / 2 / cam["fx"])) == pytest.approx(plan.fov, abs=1e-6)
        for o in rec["objects"]:
            assert all(0.03 <= c <= 0.9 for c in o["material"]["albedo"])
        depth = read_depth_exr(photo / "truth" / "depth.exr")
        assert np.isfinite(depth).all() and depth.max() <= FAR_DEPTH + 1e-3
        if plan.light == "room":
            room = generate_room(rec["room_seed"])
            area = sum((c[2] - c[0]) * (c[3] - c[1]) for c in room.cells)
            assert {"small": area < 9.0, "large": area > 40.0 or room.shell == "large"}[plan.room_kind]
            assert "captured" not in rec
            # the room as built (repainted and relit by its plan) renders the photo again bit for bit
            truth = load_truth(photo)
            scenes = RoomScenes(room_of_record(rec), cfg.max_depth)
            meshes = {o.id: o.mitsuba_mesh() for o in truth.objects}
            again = trace_image(scenes.scene(meshes), truth.camera, cfg.spp, photo_seeds(cfg, i)["photo"]) * truth.exposure
            assert np.array_equal(again, read_rgb_exr(photo / "image.exr"))
            if rec.get("edits"):   # and the seed's room alone does not
                plain = RoomScenes(room, cfg.max_depth).scene(meshes)
                assert not np.array_equal(trace_image(plain, truth.camera, cfg.spp, photo_seeds(cfg, i)["photo"])
                                          * truth.exposure, again)
        else:
            assert rec["captured"]["panorama"] == "sky.exr" and rec["room"]["type"] == "captured"
            # the camera sees the captured sky: the depth's far value, and light sources in the frame
            assert (depth >= FAR_DEPTH - 1e-3).any() and rec["emitters_in_view"] > 0
