"""roomlight.core.light.Light: validation, its frame, numpy <-> torch; and the photo camera's projection."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch

from roomlight.errors import RoomlightError, ShapeError
from roomlight.core.light import EmitterKind, Light, similarity_parts
from roomlight.fitting.photo.camera import PhotoCamera


def _maps(h: int = 4):
    rng = np.random.default_rng(0)
    return rng.random((h, 2 * h, 3), dtype=np.float32), 1.0 + rng.random((h, 2 * h), dtype=np.float32)


def _similarity(scale: float, yaw_deg: float, translation) -> np.ndarray:
    """[scale * R_y(yaw) | translation], written out by hand."""
    c, s = math.cos(math.radians(yaw_deg)), math.sin(math.radians(yaw_deg))
    m = np.eye(4)
    m[:3, :3] = scale * np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
    m[:3, 3] = translation
    return m


# ------------------------------------------------------------------------------ validation
def test_a_light_holds_its_maps_as_float32_torch_and_defaults_to_the_identity_frame():
    rad, depth = _maps()
    light = Light(rad.astype(np.float64), depth, "mesh")
    assert isinstance(light.radiance, torch.Tensor) and light.radiance.dtype == torch.float32
    assert light.depth.shape == (4, 8) and light.kind == "mesh"
    np.testing.assert_array_equal(light.frame, np.eye(4))
    assert Light(rad, None, "sphere:2.50").kind == "sphere:2.50"  # as given: records keep their spelling
    assert Light(rad, None, EmitterKind("sphere", 2.5)).kind == "sphere:2.5"


@pytest.mark.parametrize("radiance, depth, kind, error, message", [
    (np.zeros((4, 8)), None, "envmap", ShapeError, r"radiance must be \(H, 2H, 3\), got \(4, 8\)"),
    (np.zeros((4, 8, 4)), None, "envmap", ShapeError, r"radiance must be \(H, 2H, 3\)"),
    (np.zeros((4, 4, 3)), None, "envmap", ShapeError, r"got \(4, 4, 3\)"),
    (np.zeros((0, 0, 3)), None, "envmap", ShapeError, r"radiance must be"),
    (np.zeros((4, 8, 3)), np.ones((4, 4)), "mesh", ShapeError, r"depth must be \(H, W\) = \(4, 8\).*got \(4, 4\)"),
    (np.zeros((4, 8, 3)), np.ones((4, 8, 1)), "mesh", ShapeError, r"depth must be"),
    (np.zeros((4, 8, 3)), "deep", "mesh", ShapeError, r"depth is not a numeric array"),
    (np.zeros((4, 8, 3)), None, "mesh", RoomlightError, r"2.5D area light \('mesh'\) needs a depth map"),
    (np.zeros((4, 8, 3)), np.ones((4, 8)), "envmap", RoomlightError, r"'envmap' light takes no depth map"),
    (np.zeros((4, 8, 3)), np.ones((4, 8)), "sphere:3", RoomlightError, r"'sphere:3' light takes no depth map"),
    (np.zeros((4, 8, 3)), None, "area", RoomlightError, r"kind 'area': expected 'mesh', 'envmap' or 'sphere:R'"),
    (np.zeros((4, 8, 3)), None, "sphere:-1", RoomlightError, r"a sphere needs a positive radius"),
    (np.zeros((4, 8, 3)), None, "mesh:2", RoomlightError, r"expected 'mesh', 'envmap' or 'sphere:R'"),
])
def test_bad_maps_and_kinds_are_refused_with_a_message(radiance, depth, kind, error, message):
    with pytest.raises(error, match=message):
        Light(radiance, depth, kind)


@pytest.mark.parametrize("frame, message", [
    (np.eye(3), "finite 4x4 similarity"),
    (np.diag([1.0, 1.0, 1.0, 2.0]), "last row 0 0 0 1"),
    (np.diag([1.0, 2.0, 1.0, 1.0]), "uniform scale"),
    (np.diag([-1.0, 1.0, 1.0, 1.0]), "positive scale"),
    (np.full((4, 4), np.nan), "finite"),
])
def test_a_frame_that_is_not_a_similarity_is_refused(frame, message):
    rad, _ = _maps()
    with pytest.raises(RoomlightError, match=f"light frame: .*{message}"):
        Light(rad, None, "envmap", frame)


def test_the_frame_is_a_private_read_only_copy():
    rad, depth = _maps()
    m = _similarity(2.0, 30.0, (1.0, 2.0, 3.0))
    light = Light(rad, depth, "mesh", m)
    m[0, 3] = 99.0
    assert light.frame[0, 3] == 1.0
    with pytest.raises(ValueError):
        light.frame[0, 0] = 5.0


# ------------------------------------------------------------------------------ frames
def test_frames_compose_as_the_hand_computed_similarity():
    rad, depth = _maps()
    camera_to_light = _similarity(2.0, 90.0, (1.0, 0.0, -1.0))
    world_to_camera = _similarity(1.0, -90.0, (0.0, 0.0, 3.0))
    light = Light(rad, depth, "mesh", camera_to_light)
    # by hand: a world point (1, 2, 0); R_y(-90) (1, 2, 0) = (0, 2, 1), + (0, 0, 3) -> camera (0, 2, 4);
    # R_y(90) (0, 2, 4) = (4, 2, 0), x 2 = (8, 4, 0), + (1, 0, -1) -> light (9, 4, -1)
    seen = light.seen_from(world_to_camera)
    np.testing.assert_allclose(seen.frame @ [1.0, 2.0, 0.0, 1.0], [9.0, 4.0, -1.0, 1.0], atol=1e-12)
    s, r, t = similarity_parts(seen.frame)
    assert s == pytest.approx(2.0)
    np.testing.assert_allclose(r, np.eye(3), atol=1e-12)  # the two turns cancel
    np.testing.assert_allclose(t, [1.0 + 2.0 * 3.0, 0.0, -1.0], atol=1e-12)  # the world origin: camera (0, 0, 3)
    # the maps and kind go along untouched; the original keeps its frame
    assert seen.radiance is light.radiance and seen.depth is light.depth and seen.kind == "mesh"
    np.testing.assert_array_equal(light.frame, camera_to_light)
    moved = light.with_frame(np.eye(4))
    np.testing.assert_array_equal(moved.frame, np.eye(4))
    assert moved.radiance is light.radiance


# ------------------------------------------------------------------------------ numpy <-> torch
def test_numpy_and_torch_round_trip_without_a_copy():
    rad, depth = _maps()
    light = Light(rad, depth, "mesh")
    back_rad, back_depth = light.to_numpy()
    np.testing.assert_array_equal(back_rad, rad)
    np.testing.assert_array_equal(back_depth, depth)
    assert np.shares_memory(back_rad, rad)  # float32 C-contiguous input: no copy either way
    again = Light(torch.from_numpy(back_rad), torch.from_numpy(back_depth), "mesh")
    assert torch.equal(again.radiance, light.radiance) and torch.equal(again.depth, light.depth)
    env = Light(rad, None, "envmap")
    assert env.to_numpy()[1] is None
    # a read-only or strided array is copied into a tensor torch can own
    view = np.broadcast_to(rad[:1, :1], (4, 8, 3))
    assert torch.equal(Light(view, None, "envmap").radiance, torch.from_numpy(np.ascontiguousarray(view)))
    grad = torch.from_numpy(rad.copy()).requires_grad_()
    assert not Light(grad * 2, None, "envmap").radiance.requires_grad


# ------------------------------------------------------------------------------ the camera
def test_the_camera_projects_a_known_point_to_the_pixel_worked_out_by_hand():
    # 640 x 480, fx = 500, fy = 480, principal point (320, 240); x right, y up, the camera looks along -z.
    # Camera point (1, 0.5, -4): x = 320 + 500 * 1 / 4 = 445, y = 240 - 480 * 0.5 / 4 = 180, z-depth 4.
    cam = PhotoCamera(640, 480, 500.0, 480.0, 320.0, 240.0)
    xy, z = cam.project([1.0, 0.5, -4.0])
    np.testing.assert_allclose(xy, [[445.0, 180.0]])
    np.testing.assert_allclose(z, [4.0])
    # the camera moved to (2, 1, 0) and turned 90 degrees left (R_y(90): its -z looks along world -x):
    # world point (-2, 1.5, -1) is camera R^T (p - o) = R^T (-4, 0.5, -1) = (1, 0.5, -4) again
    m = np.eye(4)
    m[:3, :3] = [[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]]
    m[:3, 3] = (2.0, 1.0, 0.0)
    posed = PhotoCamera(640, 480, 500.0, 480.0, 320.0, 240.0, m)
    xy, z = posed.project([-2.0, 1.5, -1.0])
    np.testing.assert_allclose(xy, [[445.0, 180.0]], atol=1e-12)
    np.testing.assert_allclose(z, [4.0], atol=1e-12)
    # and back: the ray through film point (445, 180), as long as the point is far, reaches it
    dist = math.sqrt(1.0 + 0.25 + 16.0)
    np.testing.assert_allclose(cam.directions([445.0], [180.0])[0] * dist, [1.0, 0.5, -4.0], atol=1e-12)
    np.testing.assert_allclose(posed.origin + posed.directions([445.0], [180.0])[0] * dist, [-2.0, 1.5, -1.0],
                               atol=1e-12)


def test_one_camera_serves_the_photo_and_the_photo_benchmark():
    cam = PhotoCamera.from_fov(90.0, 200, 100)
    assert (cam.fx, cam.fy, cam.cx, cam.cy) == pytest.approx((100.0, 100.0, 100.0, 50.0))
    assert cam.fov_x == pytest.approx(90.0)
    np.testing.assert_array_equal(cam.matrix, np.eye(4))  # a photograph's own camera: identity pose
    assert cam.intrinsics_dict() == {"fx": cam.fx, "fy": cam.fy, "cx": 100.0, "cy": 50.0}
    posed = PhotoCamera.look_at((0.0, 1.0, 0.0), (0.0, 1.0, -5.0), 90.0, 200, 100)
    assert posed.intrinsics_dict() == cam.intrinsics_dict()
    assert PhotoCamera.from_dict(posed.to_dict()) == posed
    half = posed.scaled(100, 50)
    assert (half.fx, half.cx, half.cy) == pytest.approx((50.0, 50.0, 25.0))
    assert half.camera_to_world == posed.camera_to_world
    with pytest.raises(RoomlightError, match="fx, fy must be positive"):
        PhotoCamera(10, 10, 0.0, 1.0, 5.0, 5.0)
    with pytest.raises(RoomlightError, match="image size must be positive"):
        PhotoCamera(0, 10, 1.0, 1.0, 5.0, 5.0)
