"""scripts/seen_depth.py: the fitted light's depth over the photographed surfaces, on a photographed wall whose
distance from the light's centre is known in closed form."""

from __future__ import annotations

import json
from types import SimpleNamespace

import numpy as np
import pytest

from helpers_scripts import load_script


def test_a_light_built_ten_percent_behind_a_photographed_wall_reads_log2_1_1(tmp_path, monkeypatch):
    from roomlight.core.geometry.equirect import pixel_directions
    from roomlight.core.io import write_panorama
    from roomlight.fitting.photo.camera import PhotoCamera

    script = load_script("seen_depth")
    # the camera looks down -z at a wall 2 m away (z-depth 2); the light's centre 0.3 m in front of it
    cam = PhotoCamera(64, 48, 50.0, 50.0, 32.0, 24.0)
    labels = np.zeros((48, 64), np.int32)
    labels[20:28, 28:36] = 1                                   # an object: its pixels and border are left out
    case = SimpleNamespace(depth=np.full((48, 64), 2.0), intrinsics=cam, depth_kind="z",
                           objects=SimpleNamespace(labels=labels))
    monkeypatch.setattr("roomlight.fitting.photo.case.load_photo", lambda case_dir: case)
    frame = np.eye(4)
    frame[2, 3] = 0.3                                          # a camera-frame point p is p + (0, 0, 0.3) there
    h, w = 32, 64
    dirs = pixel_directions(h, w).numpy().reshape(h, w, 3).astype(np.float64)
    # the wall is the plane z = -2 + 0.3 = -1.7 in the light's frame: distance 1.7 / -d_z where d_z < 0
    wall = np.where(dirs[..., 2] < -1e-3, 1.7 / np.maximum(-dirs[..., 2], 1e-3), 50.0)
    folder = tmp_path / "cases" / "photo-a" / "prior"
    folder.mkdir(parents=True)
    (folder / "result.json").write_text(json.dumps({"case_dir": "anywhere"}))
    write_panorama(folder / "recovered.exr", (np.ones((h, w, 3), np.float32), (1.1 * wall).astype(np.float32)),
                   half=False, metadata={"emitter_kind": "mesh", "light_from_camera": frame.tolist()})
    gap, share = script.case_gap(folder)
    assert share is None
    assert len(gap) > 20
    # a texel's centre and its pixels' mean distance differ a little on a plane seen obliquely
    assert float(np.median(gap)) == pytest.approx(np.log2(1.1), abs=0.01)
    # two points in one texel give their geometric mean distance; a point in another texel its own
    hit, dist = script.seen_texels(np.array([[0.0, 0.0, -2.0], [0.0, 0.0, -8.0], [1.0, 0.0, 0.0]]), (h, w))
    assert len(hit) == 2 and sorted(dist.tolist()) == pytest.approx([1.0, 4.0])   # geometric mean of 2 and 8


def test_the_share_at_the_floor_is_rebuilt_from_the_runs_settings(tmp_path):
    """A light whose depth is the photo fit's own containment floor reads (nearly) all its seen texels at the
    floor; the same light half as far again reads none; a run without its settings is refused by name."""
    import torch

    from roomlight.core.io import write_panorama
    from roomlight.fitting.photo import case as case_mod
    from roomlight.fitting.photo.config import photo_config
    from roomlight.fitting.photo.fitter import containment_floor, containment_points
    from roomlight.fitting.photo.geometry import build_geometry, level_transform
    from roomlight.fitting.photo.synthetic import example_photo_case

    script = load_script("seen_depth")
    case_dir = tmp_path / "case"
    example_photo_case(case_dir, width=96, height=72, spp=8)
    config = photo_config("fast")
    case = case_mod.load_photo(str(case_dir), min_object_fraction=config.min_object_fraction)
    transform = level_transform(case)
    floor = containment_floor(containment_points(build_geometry(case, config), transform), (32, 64), config)
    floor = torch.where(floor > 0, floor, torch.full_like(floor, 20.0)).numpy()
    run = tmp_path / "run"
    for scale, name in ((1.0, "on"), (1.5, "off")):
        folder = run / "cases" / name / "prior"
        folder.mkdir(parents=True)
        (folder / "result.json").write_text(json.dumps({"case_dir": str(case_dir)}))
        write_panorama(folder / "recovered.exr", (np.ones((32, 64, 3), np.float32), (scale * floor).astype(np.float32)),
                       half=False, metadata={"emitter_kind": "mesh", "light_from_camera": transform.matrix.tolist()})
    settings = {"preset": "fast", "overrides": {}}
    gap, share = script.case_gap(run / "cases" / "on" / "prior", settings)
    assert share > 0.9 and len(gap) > 50
    assert float(np.median(gap)) > 0                  # the floor lies beyond the surfaces it encloses
    gap_off, share_off = script.case_gap(run / "cases" / "off" / "prior", settings)
    assert share_off == 0.0 and np.allclose(gap_off, gap + np.log2(1.5), atol=1e-5)
    with pytest.raises(SystemExit, match="no run.json"):
        script.main([str(run), "--floor"])
