"""The visible room's albedo bound: the irradiance sum against closed forms and a ray-traced reference."""

import math

import numpy as np
import pytest
import torch

from roomlight.core.geometry.equirect import direction_to_uv, pixel_directions
from roomlight.fitting.photo.room_albedo import (RoomSurface, apparent_albedo, irradiance, room_albedo_term,
                                                 surface_normals)

BOX = torch.tensor([2.0, 1.3, 1.6], dtype=torch.float64)  # half-extents of a 4 x 2.6 x 3.2 m room


def box_depth(h):
    """(h, 2h) radial depth of the box room seen from its centre."""
    d = pixel_directions(h, 2 * h, dtype=torch.float64)
    return 1.0 / (d.abs() / BOX).amax(-1)


def test_a_closed_room_of_uniform_radiance_gives_pi_l_everywhere():
    # Inside any closed surface of radiance L the irradiance is pi L, whatever the point or its normal.
    depth = box_depth(128)
    L = torch.full((128, 256, 3), 0.7, dtype=torch.float64)
    q = torch.tensor([[0.3, -1.28, 0.2], [0.0, 0.0, 0.0], [1.95, 0.5, -1.0], [1.0, 1.0, 1.0]], dtype=torch.float64)
    n = torch.tensor([[0, 1.0, 0], [0, 0, -1.0], [-1.0, 0, 0], [0, -1.0, 0]], dtype=torch.float64)
    e = irradiance(L, depth, q, n)
    assert torch.allclose(e, torch.full_like(e, math.pi * 0.7), rtol=0.03)
    # An env map of uniform radiance: the same, exactly up to the texel sum.
    e_inf = irradiance(L, None, q, n)
    assert torch.allclose(e_inf, torch.full_like(e_inf, math.pi * 0.7), rtol=2e-3)


def _bright_patch_panorama(h):
    """Radiance 0.2 everywhere, 20 on the part of the ceiling above x in [0.5, 1.5], z in [-0.5, 0.5]."""
    d = pixel_directions(h, 2 * h, dtype=torch.float64)
    p = d * box_depth(h)[..., None]
    lamp = (p[..., 1] > 1.29) & (p[..., 0] > 0.5) & (p[..., 0] < 1.5) & (p[..., 2].abs() < 0.5)
    L = torch.full((h, 2 * h, 3), 0.2, dtype=torch.float64)
    L[lamp] = 20.0
    return L


def _traced_irradiance(L, q, n, rays=400_000, seed=0):
    """Monte-Carlo reference: cosine-weighted rays from q, hit the box analytically, read the panorama's
    radiance in the hit point's direction from the centre (nearest texel)."""
    rng = np.random.default_rng(seed)
    u1, u2 = rng.random(rays), rng.random(rays)
    r, phi = np.sqrt(u1), 2 * np.pi * u2
    local = np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(1 - u1)], 1)
    n = n / np.linalg.norm(n)
    t = np.cross(n, [1.0, 0, 0] if abs(n[0]) < 0.9 else [0, 1.0, 0])
    t /= np.linalg.norm(t)
    b = np.cross(n, t)
    d = local @ np.stack([t, b, n])
    half = BOX.numpy()
    with np.errstate(divide="ignore"):
        s = np.where(d > 0, (half - q) / d, (-half - q) / d)
    hit = q + d * s.min(1, keepdims=True)
    u, v = direction_to_uv(torch.from_numpy(hit))
    h, w = L.shape[:2]
    row = np.clip((v.numpy() * h).astype(int), 0, h - 1)
    col = np.clip((u.numpy() * w).astype(int), 0, w - 1)
    return np.pi * L.numpy()[row, col].mean(0)


@pytest.mark.parametrize("q,n", [((0.9, -1.25, 0.1), (0, 1.0, 0)),      # floor under the lamp
                                 ((-1.5, -1.25, 1.2), (0, 1.0, 0)),     # floor far from it
                                 ((-1.95, 0.2, 0.0), (1.0, 0, 0)),      # the wall facing it
                                 ((0.0, 0.0, 0.0), (0.6, 0.8, 0.0))])   # a tilted point mid-room
def test_irradiance_of_a_room_with_a_lamp_matches_a_ray_traced_reference(q, n):
    L = _bright_patch_panorama(128)
    q64, n64 = np.array(q, dtype=np.float64), np.array(n, dtype=np.float64)
    ref = _traced_irradiance(L, q64, n64)
    got = irradiance(L, box_depth(128), torch.from_numpy(q64)[None], torch.from_numpy(n64 / np.linalg.norm(n64))[None])
    np.testing.assert_allclose(got[0].numpy(), ref, rtol=0.06)
    # The same lamp at infinity lights every point alike: the parallax is what the 2.5D sum adds.
    if q == (-1.5, -1.25, 1.2):
        near = irradiance(L, box_depth(128), torch.tensor([[0.9, -1.25, 0.1]], dtype=torch.float64),
                          torch.tensor([[0, 1.0, 0]], dtype=torch.float64))
        assert float(near[0, 0]) > 1.5 * float(got[0, 0])


def test_the_bound_is_zero_inside_the_range_and_the_squared_log_violation_outside():
    depth = box_depth(64)
    L = torch.full((64, 128, 3), 1.0, dtype=torch.float64)
    q = torch.tensor([[0.0, -1.25, 0.0], [0.5, 0.0, 1.55]], dtype=torch.float64)
    n = torch.tensor([[0, 1.0, 0], [0, 0, -1.0]], dtype=torch.float64)
    e = irradiance(L, depth, q, n).mean(-1)
    observed = (0.5 * e / math.pi)[:, None].expand(2, 3).float()  # walls of albedo 0.5 under this light
    room = RoomSurface(q, n, observed * 0.5)  # photo radiance halved: still albedo 0.25
    assert torch.allclose(apparent_albedo(L.float(), depth.float(), room), torch.tensor([0.25, 0.25]), rtol=1e-4)
    assert float(room_albedo_term(L.float(), depth.float(), room)) == 0.0
    # The light 0.2x as bright: apparent albedo 1.25 > 0.9.
    dim = room_albedo_term(0.2 * L.float(), depth.float(), room, trim=0.0)
    assert float(dim) == pytest.approx(math.log(1.25 / 0.9) ** 2, rel=1e-3)
    # 10x as bright: 0.025 < 0.03.
    bright = room_albedo_term(10.0 * L.float(), depth.float(), room, trim=0.0)
    assert float(bright) == pytest.approx(math.log(0.03 / 0.025) ** 2, rel=1e-3)
    # The gradient of a too-dim light points to a brighter one.
    s = torch.tensor(math.log(0.2), requires_grad=True)
    room_albedo_term(torch.exp(s) * L.float(), depth.float(), room, trim=0.0).backward()
    assert float(s.grad) < 0


def test_saturated_pixels_and_the_worst_points_are_left_out():
    depth = box_depth(64).float()
    L = torch.full((64, 128, 3), 0.2)  # E = 0.2 pi
    q = torch.tensor([[0.0, -1.25, 0.0]] * 10)
    n = torch.tensor([[0, 1.0, 0]] * 10)
    obs = torch.full((10, 3), 0.1)  # albedo 0.5: fine
    obs[0] = 1.0                     # saturated: a lamp, unknown radiance
    obs[1] = 0.95                    # unsaturated but albedo 4.75: a lamp shade, trimmed
    room = RoomSurface(q, n, obs)
    # 9 unsaturated points: a trim of 0.2 leaves out floor(1.8) = 1, the shade.
    assert float(room_albedo_term(L, depth, room, trim=0.2)) == 0.0
    # Without the trim the shade's violation, averaged over the 9 points.
    assert float(room_albedo_term(L, depth, room, trim=0.0)) == pytest.approx(math.log(4.75 / 0.9) ** 2 / 9, rel=0.02)


def test_normals_of_a_depth_grid_face_the_camera_and_edges_are_flagged():
    # A floor 1 m below the camera and a wall 6 m ahead.
    h, w = 200, 250
    ys, xs = np.mgrid[0:h, 0:w]
    rays = np.stack([(xs + 0.5 - w / 2) / (w / 2) * 0.6, -(ys + 0.5 - h / 2) / (h / 2) * 0.5, -np.ones((h, w))], -1)
    t_floor = np.where(rays[..., 1] < 0, -1.0 / np.minimum(rays[..., 1], -1e-9), np.inf)
    t_wall = 6.0 / -rays[..., 2]
    t = np.minimum(t_floor, t_wall)
    pts = rays * t[..., None]
    normals, ok = surface_normals(pts)
    on_floor = (t_floor < t_wall * 0.97) & ok
    on_wall = (t_wall < t_floor * 0.97) & ok
    assert on_floor.sum() > 100 and on_wall.sum() > 100
    np.testing.assert_allclose(normals[on_floor], np.tile([0, 1.0, 0], (on_floor.sum(), 1)), atol=1e-6)
    np.testing.assert_allclose(normals[on_wall], np.tile([0, 0, 1.0], (on_wall.sum(), 1)), atol=1e-6)
    assert not ok[0].any() and not ok[:, -1].any()  # no two-sided neighbourhood at the border


def _irradiance_pair_by_pair(L, depth, q, nq, min_cosine=0.1):
    """The texel sum written out per (point, texel) pair with explicit difference vectors: the slow,
    obvious form of the same formula (no pooling: L and depth at the grid they are given)."""
    h, w = depth.shape
    dirs = pixel_directions(h, w, dtype=depth.dtype)
    from roomlight.core.geometry.equirect import pixel_solid_angles
    omega = pixel_solid_angles(h, w, dtype=depth.dtype)
    pos = dirs * depth[..., None]
    du = torch.roll(pos, -1, 1) - torch.roll(pos, 1, 1)
    dv = torch.cat([pos[1:], pos[-1:]], 0) - torch.cat([pos[:1], pos[:-1]], 0)
    nt = torch.nn.functional.normalize(torch.cross(du, dv, dim=-1), dim=-1)
    nt = torch.where((nt * dirs).sum(-1, keepdim=True) > 0, -nt, nt)
    area = depth.square() * omega / (nt * dirs).sum(-1).abs().clamp_min(min_cosine)
    out = []
    for qi, ni in zip(q, nq):
        e = torch.zeros(3, dtype=L.dtype)
        for y in range(h):
            for x in range(w):
                diff = pos[y, x] - qi
                r2 = torch.maximum(diff.square().sum(), area[y, x] / (2 * math.pi))
                d = diff / r2.sqrt()
                solid = torch.clamp(area[y, x] * torch.clamp(-(d * nt[y, x]).sum(), min=0) / r2, max=2 * math.pi)
                e = e + L[y, x] * torch.clamp((d * ni).sum(), min=0) * solid
        out.append(e)
    return torch.stack(out)


def test_the_texel_sum_and_its_gradient_equal_the_pair_by_pair_formula():
    # 8 x 16 texels (pooled_height above it: no pooling), a lamp, three points: one in the middle of the
    # room, one 1 cm off the floor (its texel's floor is active), one facing a wall.
    torch.manual_seed(3)
    depth = (box_depth(8) * (1 + 0.1 * torch.rand(8, 16, dtype=torch.float64))).requires_grad_()
    L = (0.2 + torch.rand(8, 16, 3, dtype=torch.float64)).requires_grad_()
    q = torch.tensor([[0.1, 0.2, -0.3], [0.4, -1.29, 0.3], [1.5, 0.0, 0.5]], dtype=torch.float64)
    n = torch.nn.functional.normalize(torch.tensor([[0.3, 1.0, 0.2], [0, 1.0, 0], [-1.0, 0.1, 0]],
                                                   dtype=torch.float64), dim=-1)
    got = irradiance(L, depth, q, n)
    ref = _irradiance_pair_by_pair(L, depth, q, n)
    assert torch.allclose(got, ref, rtol=1e-10, atol=1e-12)
    g_got = torch.autograd.grad(got.square().sum(), (L, depth))
    g_ref = torch.autograd.grad(ref.square().sum(), (L, depth))
    for a, b in zip(g_got, g_ref):
        assert torch.allclose(a, b, rtol=1e-8, atol=1e-10)


def test_the_level_bracket_is_the_trimmed_albedo_quantiles_over_the_range():
    # Under an env map of uniform radiance L every point receives E = pi L, so a point showing a L has
    # apparent albedo a: the bracket follows from the albedos by hand.
    from roomlight.fitting.photo.room_albedo import level_bracket

    L = torch.full((64, 128, 3), 0.4)
    albedos = [0.05 * (i + 1) for i in range(11)]            # 0.05 ... 0.55
    n = torch.tensor([[0.0, 1.0, 0.0]] * 12)
    n = torch.tensor([[0.0, 1.0, 0.0]] * 13)
    q = torch.zeros(13, 3)
    # the last two: saturated (only a lower bound) and black (only an upper bound)
    obs = torch.tensor([[a * 0.4] * 3 for a in albedos] + [[1.0, 1.0, 1.0], [0.0, 0.0, 0.0]])
    room = RoomSurface(q, n, obs)
    b = level_bracket(L, None, room, trim=0.1)
    assert b["points"] == 11 and b["albedo_range"] == [0.03, 0.9]   # neither censored pixel takes part
    # Trimming a tenth at each end of 11 sorted values keeps the 2nd to the 10th: 0.10 and 0.50.
    assert b["albedo_quantiles"] == pytest.approx([0.10, 0.50], rel=3e-3)
    assert b["low"] == pytest.approx(0.50 / 0.9, rel=3e-3)    # brighter than this: the whitest below 0.9
    assert b["high"] == pytest.approx(0.10 / 0.03, rel=3e-3)  # dimmer than this: the darkest above 0.03
    # A light twice as bright allows half the factors.
    b2 = level_bracket(2 * L, None, room, trim=0.1)
    assert (b2["low"], b2["high"]) == pytest.approx((b["low"] / 2, b["high"] / 2), rel=1e-5)
    # A room that needs a white above 0.9 and a black below 0.03 under one light: the bracket is empty.
    wide = RoomSurface(torch.zeros(2, 3), n[:2], torch.tensor([[0.01 * 0.4] * 3, [0.95 * 0.4] * 3]))
    e = level_bracket(L, None, wide, trim=0.0)
    assert e["low"] > e["high"]
    # Nothing unsaturated: no bracket.
    assert level_bracket(L, None, RoomSurface(q[:2], n[:2], obs[-2:]), trim=0.1) is None


def test_the_level_line_says_whether_the_fitted_light_is_inside_its_bracket():
    from roomlight.fitting.photo.outputs import level_note

    record = {"points": 900, "trim": 0.1, "albedo_range": [0.03, 0.9]}
    inside = level_note({**record, "low": 0.5, "high": 2.0})
    assert "x0.50 to x2.00 (2.0 stops)" in inside and "the fitted level lies inside" in inside
    assert "80% of the visible room's 900 measured points" in inside
    assert "dimmer than that allows" in level_note({**record, "low": 1.3, "high": 4.0})
    assert "brighter than that allows" in level_note({**record, "low": 0.2, "high": 0.8})
    assert "(0.05) and white (0.8)" in level_note({**record, "albedo_range": [0.05, 0.8], "low": 0.5, "high": 2.0})
    # empty, or collapsed to nothing by black points: no range, and no division by zero
    for low, high in ((3.0, 2.0), (0.0, 0.0)):
        assert "no one scale of this light" in level_note({**record, "low": low, "high": high})
