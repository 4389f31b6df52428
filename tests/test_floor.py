"""The depth floor keeps points inside a 2.5D area light, checked by casting rays at its mesh."""

from __future__ import annotations

import numpy as np
import torch

from roomlight.core.emitter.area_light import build_area_light
from roomlight.fitting.inverse.floor import apply_floor, depth_floor, outside_share


def _first_hits(vertices: np.ndarray, faces: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """Distance from the origin to the nearest triangle along each direction (Moller-Trumbore,
    both faces; inf where nothing is hit)."""
    v0, v1, v2 = (vertices[faces[:, k]] for k in range(3))
    e1, e2 = v1 - v0, v2 - v0
    out = np.full(len(directions), np.inf)
    for n, d in enumerate(directions):
        p = np.cross(d, e2)
        det = np.einsum("ij,ij->i", e1, p)
        ok = np.abs(det) > 1e-12
        inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
        s = -v0
        u = np.einsum("ij,ij->i", s, p) * inv
        q = np.cross(s, e1)
        v = (q @ d) * inv
        t = np.einsum("ij,ij->i", e2, q) * inv
        hit = ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0)
        if hit.any():
            out[n] = t[hit].min()
    return out


def test_points_beyond_a_small_room_end_up_inside_its_mesh():
    h, w = 16, 32
    depth = torch.full((h, w), 1.0)                          # a 1 m room
    rng = np.random.default_rng(0)
    dirs = rng.normal(size=(300, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    dist = rng.uniform(0.5, 3.0, size=300)
    points = torch.from_numpy(dirs * dist[:, None])
    assert outside_share(depth, points) > 0.5
    floor = depth_floor(points, (h, w), margin=0.05)
    lifted = apply_floor(depth, floor)
    assert outside_share(lifted, points) == 0.0
    mesh = build_area_light(torch.ones(h, w, 3), lifted)
    hits = _first_hits(mesh.vertices.double().numpy(), mesh.faces.numpy(), dirs)
    assert np.all(hits > dist)                               # the ray leaves the point before the light
    # where no point asks for more, the room keeps its depth and its gradient
    untouched = floor == 0
    assert bool(untouched.any()) and bool((lifted[untouched] == 1.0).all())


def test_floor_is_the_dilated_maximum_of_the_points_distances():
    h, w = 8, 16
    # one point straight ahead (-z: column 0 / 15 boundary at u = 0), 2 m away
    floor = depth_floor(torch.tensor([[0.0, 0.0, -2.0]]), (h, w), margin=0.1, relative=0.0)
    need = 2.1
    rows, cols = torch.nonzero(floor > 0, as_tuple=True)
    # v = 0.5 is row 4 of 8; u = 0 is column 0, and the 3 x 3 neighbourhood wraps to column 15
    assert set(rows.tolist()) == {3, 4, 5} and set(cols.tolist()) == {15, 0, 1}
    assert len(rows) == 9 and bool((floor[rows, cols] == np.float32(need)).all())


def test_floor_passes_gradient_where_the_room_is_already_larger():
    depth = torch.full((8, 16), 3.0, requires_grad=True)
    floor = depth_floor(torch.tensor([[0.0, 0.0, -1.0]]), (8, 16))
    apply_floor(depth, floor).sum().backward()
    assert bool((depth.grad == 1).all())
