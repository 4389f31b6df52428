from collections import Counter

import pytest
import torch

from roomlight.core.emitter.area_light import area_light_topology, area_light_vertices, build_area_light
from roomlight.core.emitter.envmap import envmap_data
from roomlight.errors import ShapeError
from roomlight.core.geometry import pixel_directions


def star_depth(h, w, seed=0, dtype=torch.float64):
    g = torch.Generator().manual_seed(seed)
    return 0.5 + 3.0 * torch.rand(h, w, generator=g, dtype=dtype)


def veni_d_depth(h, w, seed=0, dtype=torch.float64):
    """The depth VENI+D decodes from a random latent (untrained network, scaled to a room)."""
    from roomlight.prior.model.normalization import Normalization
    from roomlight.prior.model.veni import VeniConfig, VeniVAE

    torch.manual_seed(seed)
    cfg = VeniConfig(resolution=(h, w), latent_vectors=4, depth=True, channels=8, invariants=2, blocks=1, heads=2,
                     field_width=16, field_blocks=1)
    m = VeniVAE(cfg, Normalization(mean=(0.3, 0.3, 0.3, 1.0), std=(0.5, 0.5, 0.5, 0.5))).to(dtype)
    with torch.no_grad():
        return m.decode(torch.randn(1, cfg.latent_dim, dtype=dtype))[1][0, 0]


#: The depth maps every mesh test runs on: random ones and VENI+D's decodings.
DEPTHS = pytest.mark.parametrize("depth_of", [star_depth, veni_d_depth], ids=["random", "veni-d"])


def weld(vertices, faces, decimals=9):
    """Merge coincident vertices (seam and pole duplicates) -> welded faces."""
    key = torch.round(vertices * 10**decimals).to(torch.int64)
    _, inverse = torch.unique(key, dim=0, return_inverse=True)
    return inverse[faces]


@DEPTHS
@pytest.mark.parametrize("hw", [(2, 4), (5, 10), (16, 32)])
def test_welded_mesh_is_closed_and_consistently_oriented(hw, depth_of):
    h, w = hw
    depth = depth_of(h, w)
    mesh = build_area_light(torch.rand(h, w, 3, dtype=torch.float64), depth)
    assert mesh.faces.shape == (2 * h * w, 3)
    assert mesh.vertices.shape == (h * (w + 1) + 2 * w, 3)
    f = weld(mesh.vertices, mesh.faces)
    # no degenerate faces after welding
    assert ((f[:, 0] != f[:, 1]) & (f[:, 1] != f[:, 2]) & (f[:, 0] != f[:, 2])).all()
    edges = Counter()
    for a, b, c in f.tolist():
        for e in ((a, b), (b, c), (c, a)):
            edges[e] += 1
    assert all(n == 1 for n in edges.values()), "a directed edge is used twice: inconsistent orientation"
    assert all(edges[(b, a)] == 1 for (a, b) in edges), "an edge has no reverse: the mesh is open"
    # Euler characteristic of a sphere
    nv = int(torch.unique(f).numel())
    assert nv - len(edges) // 2 + f.shape[0] == 2


@DEPTHS
def test_faces_point_towards_the_capture_point(depth_of):
    h, w = 16, 32
    v = area_light_vertices(depth_of(h, w, seed=3))
    f = area_light_topology(h, w).faces
    n = torch.linalg.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    centroid = v[f].mean(1)
    assert ((n * centroid).sum(-1) < 0).all()


@DEPTHS
def test_vertices_are_depth_times_direction_and_poles_are_ring_centroids(depth_of):
    h, w = 6, 12
    depth = depth_of(h, w, seed=1)
    v = area_light_vertices(depth)
    grid = v[: h * (w + 1)].reshape(h, w + 1, 3)
    ref = depth[..., None] * pixel_directions(h, w, dtype=torch.float64)
    assert torch.allclose(grid[:, :w], ref, atol=1e-12)
    assert torch.allclose(grid[:, w], ref[:, 0], atol=1e-12)  # seam duplicate
    north = v[h * (w + 1): h * (w + 1) + w]
    south = v[h * (w + 1) + w:]
    assert torch.allclose(north, ref[0].mean(0).expand(w, 3), atol=1e-12)
    assert torch.allclose(south, ref[-1].mean(0).expand(w, 3), atol=1e-12)


def test_uvs_index_pixel_centres():
    h, w = 4, 8
    topo = area_light_topology(h, w)
    uv = topo.uv[: h * (w + 1)].reshape(h, w + 1, 2)
    assert torch.allclose(uv[2, 3], torch.tensor([3.5 / w, 2.5 / h]))
    assert torch.allclose(uv[1, w], torch.tensor([1 + 0.5 / w, 1.5 / h]))


def test_topology_is_cached_per_resolution():
    assert area_light_topology(8, 16) is area_light_topology(8, 16)
    assert area_light_topology(8, 16) is not area_light_topology(4, 8)


def test_mesh_builder_gradcheck():
    h, w = 3, 6
    depth = star_depth(h, w).requires_grad_()
    assert torch.autograd.gradcheck(lambda d: area_light_vertices(d), (depth,))
    rad = torch.rand(h, w, 3, dtype=torch.float64, requires_grad=True)
    assert torch.autograd.gradcheck(lambda r, d: build_area_light(r, d).vertices.sum() + build_area_light(r, d).texture.sum(), (rad, depth))


def test_envmap_resampling_gradcheck():
    rad = torch.rand(4, 8, 3, dtype=torch.float64, requires_grad=True)
    assert envmap_data(rad).shape == (5, 10, 3)
    assert torch.autograd.gradcheck(envmap_data, (rad,))


def test_bad_shapes():
    with pytest.raises(ShapeError, match="width = 2 x height"):
        area_light_vertices(torch.ones(4, 6))
    with pytest.raises(ShapeError, match="resample"):
        build_area_light(torch.ones(4, 8, 3), torch.ones(8, 16))
