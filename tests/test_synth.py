"""Procedural rooms: exact depth, energy, determinism, splits/shards, plausibility."""

import hashlib

import numpy as np
import pytest
import torch

from roomlight.geometry import box_distance, pixel_directions

pytestmark = pytest.mark.mitsuba


def _box_scene(mi, lo, hi, emit=None):
    """An axis-aligned box room [lo, hi]; with ``emit`` its inner faces emit that radiance."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    c, half = (lo + hi) / 2, (hi - lo) / 2
    shape = {"type": "cube", "to_world": mi.ScalarTransform4f().translate(c.tolist()).scale(half.tolist()),
             "flip_normals": True,
             "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.0, 0.0, 0.0]}}}
    if emit is not None:
        shape["emitter"] = {"type": "area", "radiance": {"type": "rgb", "value": [emit] * 3}}
    return mi.load_dict({"type": "scene", "integrator": {"type": "path", "max_depth": 6}, "room": shape})


def test_depth_equals_analytic_ray_box_distance(mi):
    from roomlight.synth.camera import render_depth

    lo, hi, origin = (-2.0, -1.4, -3.1), (2.6, 1.2, 1.7), (0.3, 0.1, -0.4)
    scene = _box_scene(mi, lo, hi)
    depth = render_depth(scene, origin, height=32)
    ref = box_distance(pixel_directions(32, 64, dtype=torch.float64), lo, hi, origin).numpy()
    assert np.max(np.abs(depth - ref) / ref) <= 1e-4


def test_closed_emissive_room_with_zero_albedo_renders_one(mi):
    from roomlight.synth.camera import render_radiance

    scene = _box_scene(mi, (-2, -1.5, -2.5), (3, 1.5, 2), emit=1.0)
    rad = render_radiance(scene, (0.2, 0.0, -0.3), height=16, spp=16, seed=3)
    assert np.allclose(rad, 1.0, atol=1e-5)


@pytest.fixture(scope="module")
def small_set(tmp_path_factory):
    from roomlight.synth.dataset import SynthConfig, generate_dataset

    out = tmp_path_factory.mktemp("rooms")
    summary = generate_dataset(out, SynthConfig(n=4, seed0=10, height=8, spp=4), progress=False)
    return out, summary


def _digest(p):
    return hashlib.sha256(p.read_bytes()).hexdigest()


def test_same_seed_same_file_and_different_seeds_differ(small_set, tmp_path):
    from roomlight.io import read_panorama
    from roomlight.synth.dataset import SynthConfig, generate_dataset

    out, summary = small_set
    assert summary["failed"] == {} and summary["rendered"] == 4
    again = tmp_path / "again"
    generate_dataset(again, SynthConfig(n=4, seed0=10, height=8, spp=4), progress=False)
    files = sorted(out.glob("*/room-*.exr"))
    assert len(files) == 4
    for f in files:
        assert _digest(f) == _digest(again / f.parent.name / f.name)
    a, b = (read_panorama(f) for f in files[:2])
    assert a.metadata["room"] != b.metadata["room"] or not np.array_equal(a.depth, b.depth)


def test_resume_skips_finished_samples(small_set):
    from roomlight.synth.dataset import SynthConfig, generate_dataset

    out, _ = small_set
    s = generate_dataset(out, SynthConfig(n=4, seed0=10, height=8, spp=4), progress=False)
    assert s["rendered"] == 0 and s["skipped_existing"] == 4


def test_splits_and_shards_partition_the_seed_range():
    from roomlight.synth.dataset import split_of

    n, seed0 = 50, 100
    splits = [split_of(s, seed0, n) for s in range(seed0, seed0 + n)]
    assert splits.count("test") == 5 and splits.count("val") == 5 and splits.count("train") == 40
    assert splits == sorted(splits, key=["train", "val", "test"].index)  # contiguous seed ranges
    k = 3
    shards = [[s for s in range(seed0, seed0 + n) if s % k == i] for i in range(k)]
    assert sorted(sum(shards, [])) == list(range(seed0, seed0 + n))


def test_rooms_are_lit_finite_and_positive(small_set):
    from roomlight.io import read_panorama

    out, _ = small_set
    for f in sorted(out.glob("*/room-*.exr")):
        p = read_panorama(f)
        assert np.isfinite(p.radiance).all() and (p.radiance >= 0).all()
        assert np.isfinite(p.depth).all() and (p.depth > 0).all()
        room = p.metadata["room"]
        assert room["lights_on"] + room["windows"] >= 1       # some emitter lights the room
        assert p.radiance.max() > 1.0                           # ... and reaches the capture point
        assert abs(p.metadata["exposure_factor"]) > 0


def test_bad_arguments_are_clean_errors(tmp_path):
    from roomlight.errors import RoomlightError
    from roomlight.synth.dataset import SynthConfig, generate_dataset

    with pytest.raises(RoomlightError, match="perfect square"):
        generate_dataset(tmp_path, SynthConfig(n=1, height=8, spp=10), progress=False)
    with pytest.raises(RoomlightError, match="shard"):
        generate_dataset(tmp_path, SynthConfig(n=1, height=8, spp=4, shard=(2, 2)), progress=False)


def test_capture_point_is_at_eye_height_and_clear_of_surfaces():
    from roomlight.synth.rooms import capture_clearance, generate_room

    for seed in range(12):
        room = generate_room(seed)
        assert 0.9 <= room.capture[1] <= 1.8
        assert 2.3 <= room.height <= 4.0
        assert capture_clearance(room) >= 0.4, seed
