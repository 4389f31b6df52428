"""scripts/albedo_consistency.py: the seen room's and the light's unseen texels' apparent albedos, against
the closed form of a room of uniform radiance (E = pi L everywhere inside, so every texel reflects 1)."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from helpers_scripts import load_script


def _script():
    return load_script("albedo_consistency")


def _box_depth(h, half=(2.0, 1.3, 1.6)):
    from roomlight.core.geometry.equirect import pixel_directions

    d = pixel_directions(h, 2 * h, dtype=torch.float64)
    return (1.0 / (d.abs() / torch.tensor(half, dtype=torch.float64)).amax(-1)).float()


def _camera():
    from roomlight.fitting.photo.camera import PhotoCamera

    return PhotoCamera(64, 48, 40.0, 40.0, 32.0, 24.0)


def test_points_in_front_of_the_camera_and_inside_its_frame_are_seen():
    seen = _script()._seen_in_camera(np.array([[0, 0, -2.0], [0, 0, 2.0], [3.0, 0, -1.0], [0.5, -0.4, -2.0]]),
                                     np.eye(4), _camera())
    # ahead; behind; far to the right (u = 32 + 40 * 3 = 152 > 64); low and right, inside (u 42, v 32)
    assert seen.tolist() == [True, False, False, True]
    # a light frame that turns the room half a turn about the vertical puts "behind" in front
    half_turn = np.diag([-1.0, 1.0, -1.0, 1.0])
    assert _script()._seen_in_camera(np.array([[0, 0, 2.0]]), half_turn, _camera()).tolist() == [True]


def test_a_uniform_room_gives_texels_of_albedo_one_and_the_floor_its_own():
    from roomlight.core.light import Light

    script = _script()
    L, rho = 0.7, 0.25
    light = Light(torch.full((64, 128, 3), L), _box_depth(64), "mesh", np.eye(4))
    # the visible floor (y = -1.3), 0.2 m in front of the camera and beyond, reflecting rho of its irradiance
    rng = np.random.default_rng(0)
    pts = np.column_stack([rng.uniform(-1, 1, 40), np.full(40, -1.29), rng.uniform(-1.4, -0.2, 40)])
    nrm = np.tile([0.0, 1.0, 0.0], (40, 1))
    rad = np.full((40, 3), rho * L)
    out = script.apparent_albedos(light, (pts, nrm, rad), _camera())
    assert abs(out["seen"] - rho) < 0.03 * rho
    assert abs(out["unseen"] - 1.0) < 0.05
    assert 0 < out["texels"] < 32 * 64


def test_a_folder_that_is_not_a_benchmark_run_is_refused_in_one_line(tmp_path):
    with pytest.raises(SystemExit, match="not a `roomlight bench run-photos` folder"):
        _script().main([str(tmp_path)])
