"""Procedural rooms, rendering: exact depth and energy of the synth camera and scene builder."""

import numpy as np
import pytest
import torch

from roomlight.core.geometry import box_distance, pixel_directions

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
    from roomlight.datagen.synth.camera import render_depth

    lo, hi, origin = (-2.0, -1.4, -3.1), (2.6, 1.2, 1.7), (0.3, 0.1, -0.4)
    scene = _box_scene(mi, lo, hi)
    depth = render_depth(scene, origin, height=32)
    ref = box_distance(pixel_directions(32, 64, dtype=torch.float64), lo, hi, origin).numpy()
    assert np.max(np.abs(depth - ref) / ref) <= 1e-4


def test_closed_emissive_room_with_zero_albedo_renders_one(mi):
    from roomlight.datagen.synth.camera import render_radiance

    scene = _box_scene(mi, (-2, -1.5, -2.5), (3, 1.5, 2), emit=1.0)
    rad = render_radiance(scene, (0.2, 0.0, -0.3), height=16, spp=16, seed=3)
    assert np.allclose(rad, 1.0, atol=1e-5)


# -- generator, scene builder and window portals (roomlight.datagen.synth internals) ---------------------

def _rotated_directions(h, yaw):
    d = pixel_directions(h, 2 * h, dtype=torch.float64)
    c, s = np.cos(yaw), np.sin(yaw)
    x, y, z = d.unbind(-1)
    return torch.stack([c * x + s * z, y, -s * x + c * z], -1)


def test_depth_of_built_box_room_with_yaw(mi):
    """The room builder's shell (quads with 1 mm overlaps) and the yaw convention."""
    from roomlight.datagen.synth.camera import render_depth
    from roomlight.datagen.synth.rooms import box_room
    from roomlight.datagen.synth.scene import build_scene

    yaw = 0.7
    room = box_room(size=(4.2, 2.6, 5.3), capture=(1.1, 1.5, 3.2), yaw=yaw, light=False)
    depth = render_depth(build_scene(room), room.capture, height=32, yaw=yaw)
    ref = box_distance(_rotated_directions(32, yaw), (0, 0, 0), (4.2, 2.6, 5.3), room.capture).numpy()
    assert np.max(np.abs(depth - ref) / ref) <= 1e-4


def test_built_emissive_box_room_with_zero_albedo_renders_one(mi):
    from roomlight.datagen.synth.camera import render_radiance
    from roomlight.datagen.synth.rooms import box_room
    from roomlight.datagen.synth.scene import build_scene

    room = box_room(albedo=(0.0, 0.0, 0.0), emission=(1.0, 1.0, 1.0))
    rad = render_radiance(build_scene(room), room.capture, height=16, spp=4, seed=1, yaw=0.3)
    assert np.allclose(rad, 1.0, atol=1e-5)
