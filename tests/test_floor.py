"""The depth floor keeps points inside a 2.5D area light, checked by casting rays at its mesh."""

from __future__ import annotations

import numpy as np
import pytest
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


def test_a_cell_only_floor_lifts_the_points_own_cell_and_the_vertex_there_is_beyond_it():
    """neighbours=False: the need of a point lands in its own cell alone; on a 1 m room, every point's own cell
    centre (a mesh vertex) is then at least the point's distance away, while the enclosing floor's guarantee
    (the ray leaves the point before it meets the mesh) no longer holds for all of them."""
    floor = depth_floor(torch.tensor([[0.0, 0.0, -2.0]]), (8, 16), margin=0.1, relative=0.0, neighbours=False)
    rows, cols = torch.nonzero(floor > 0, as_tuple=True)
    assert rows.tolist() == [4] and cols.tolist() == [0] and float(floor[4, 0]) == np.float32(2.1)
    h, w = 16, 32
    rng = np.random.default_rng(1)
    dirs = rng.normal(size=(400, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    dist = rng.uniform(0.5, 3.0, size=400)
    points = torch.from_numpy(dirs * dist[:, None])
    cell_floor = depth_floor(points, (h, w), relative=0.0, neighbours=False)
    spread = depth_floor(points, (h, w), relative=0.0)
    assert bool((cell_floor <= spread).all()) and float(cell_floor.sum()) < float(spread.sum())
    v = np.arctan2(np.hypot(dirs[:, 0], dirs[:, 2]), dirs[:, 1]) / np.pi
    u = np.mod(np.arctan2(dirs[:, 0], -dirs[:, 2]) / (2 * np.pi), 1.0)
    own = cell_floor.numpy()[np.minimum((v * h).astype(int), h - 1), np.minimum((u * w).astype(int), w - 1)]
    assert np.all(own >= np.float32(dist) * (1 - 1e-6))
    lifted = apply_floor(torch.full((h, w), 1.0), cell_floor)
    mesh = build_area_light(torch.ones(h, w, 3), lifted)
    hits = _first_hits(mesh.vertices.double().numpy(), mesh.faces.numpy(), dirs)
    assert np.any(hits <= dist)                               # some rays meet a nearer neighbour's triangle first


def test_the_floor_of_two_point_sets_is_the_larger_of_their_floors():
    """The photo fit floors the objects (with their margin) and the visible room apart and keeps the larger:
    with the enclosing floor for both this is the floor of all the points at once."""
    rng = np.random.default_rng(4)
    a, b = (torch.from_numpy(rng.normal(size=(n, 3)) * 2.0) for n in (50, 70))
    margin = torch.from_numpy(np.concatenate([np.full(50, 0.1), np.zeros(70)]))
    together = depth_floor(torch.cat([a, b]), (16, 32), margin)
    apart = torch.maximum(depth_floor(a, (16, 32), 0.1), depth_floor(b, (16, 32)))
    assert torch.equal(together, apart)
    assert torch.equal(depth_floor(torch.zeros(0, 3, dtype=torch.float64), (16, 32)), torch.zeros(16, 32))


def test_the_photo_fit_floors_objects_over_their_neighbours_and_the_seen_room_as_asked():
    """containment_floor: an object's vertex always lifts the 3 x 3 cells around it (with the margin); a point of
    the visible room lifts them too by default and only its own cell with surface_floor=cell."""
    from roomlight.fitting.photo.config import photo_config
    from roomlight.fitting.photo.fitter import containment_floor

    surface = np.array([[0.0, 0.0, -2.0]])                 # straight ahead: row 4, column 0 of 8 x 16
    objects = np.array([[0.0, 0.0, 1.0]])                  # straight behind: row 4, column 8
    contained = (surface, objects)
    for setting, surface_cells in (("neighbours", 9), ("cell", 1)):
        config = photo_config("fast", surface_floor=setting, margin=0.1)
        floor = containment_floor(contained, (8, 16), config)
        ahead, behind = floor[:, [15, 0, 1]], floor[:, 7:10]
        assert int((ahead > 0).sum()) == surface_cells and float(floor[4, 0]) == pytest.approx(2.0 * 1.02)
        assert int((behind > 0).sum()) == 9 and float(floor[4, 8]) == pytest.approx(1.0 * 1.02 + 0.1)
        assert int((floor > 0).sum()) == surface_cells + 9
