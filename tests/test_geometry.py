import math

import numpy as np
import pytest
import torch

from roomlight.errors import ShapeError
from roomlight.core.geometry import (
    direction_to_uv, latitude_channels, panorama_to_perspective, perspective_to_panorama,
    pixel_directions, pixel_solid_angles, pixel_uv, rotate_panorama, rotation_matrix,
    sample_equirect, spherical_pad, uv_to_direction,
)


def smooth_pano(h, w, dtype=torch.float64):
    """A smooth function of direction (no seam or pole artefacts by construction)."""
    d = pixel_directions(h, w, dtype=dtype)
    return smooth_fn(d).permute(2, 0, 1)[None]


def smooth_fn(d):
    x, y, z = d.unbind(-1)
    return torch.stack([1.5 + torch.sin(3 * x + 1) * torch.cos(2 * y), 1 + 0.8 * torch.sin(4 * z), 0.5 + 0.5 * y], -1)


def test_documented_axes():
    # u = 0 looks along -z, u = 0.25 along +x, u = 0.5 along +z; row 0 is the zenith.
    t = torch.tensor
    assert torch.allclose(uv_to_direction(t(0.0), t(0.5)), t([0.0, 0.0, -1.0]), atol=1e-7)
    assert torch.allclose(uv_to_direction(t(0.25), t(0.5)), t([1.0, 0.0, 0.0]), atol=1e-7)
    assert torch.allclose(uv_to_direction(t(0.5), t(0.5)), t([0.0, 0.0, 1.0]), atol=1e-7)
    assert torch.allclose(uv_to_direction(t(0.3), t(0.0)), t([0.0, 1.0, 0.0]), atol=1e-7)


def test_uv_direction_round_trip():
    g = torch.Generator().manual_seed(0)
    u = torch.rand(10000, generator=g, dtype=torch.float64)
    v = torch.rand(10000, generator=g, dtype=torch.float64) * 0.999 + 0.0005
    u2, v2 = direction_to_uv(uv_to_direction(u, v))
    du = torch.remainder(u2 - u + 0.5, 1.0) - 0.5
    assert du.abs().max() < 1e-12 and (v2 - v).abs().max() < 1e-12
    # pixel centres, and non-unit directions
    uv = pixel_uv(16, 32, dtype=torch.float64)
    d = pixel_directions(16, 32, dtype=torch.float64) * 3.7
    u3, v3 = direction_to_uv(d)
    assert torch.allclose(u3, uv[..., 0], atol=1e-12) and torch.allclose(v3, uv[..., 1], atol=1e-12)


def test_direction_to_uv_accurate_near_poles():
    eps = 1e-9
    u, v = direction_to_uv(torch.tensor([eps, 1.0, 0.0], dtype=torch.float64))
    assert abs(float(v) - eps / math.pi) < 1e-15


def test_solid_angles_sum_to_4pi_and_match_quadrature():
    for h in (4, 17, 128):
        sa = pixel_solid_angles(h, 2 * h, dtype=torch.float64)
        assert abs(float(sa.sum()) - 4 * math.pi) < 1e-10
    # independent reference: midpoint quadrature of sin(theta) over one pixel
    h, w, i = 8, 16, 3
    th = np.linspace(i * np.pi / h, (i + 1) * np.pi / h, 20001)
    ref = np.trapezoid(np.sin(th), th) * 2 * np.pi / w
    assert abs(float(pixel_solid_angles(h, w, dtype=torch.float64)[i, 5]) - ref) < 1e-9


def test_latitude_channels():
    ch = latitude_channels(4, 8, dtype=torch.float64)
    theta = (torch.arange(4, dtype=torch.float64) + 0.5) * math.pi / 4
    assert torch.allclose(ch[0, :, 3], torch.cos(theta)) and torch.allclose(ch[1, :, 0], torch.sin(theta))


def test_shape_check():
    with pytest.raises(ShapeError, match="width = 2 x height"):
        sample_equirect(torch.zeros(1, 3, 10, 10), torch.tensor([[0.0, 0.0, -1.0]]))


def slow_spherical_pad(x, p):
    """Obvious per-pixel reference: map each padded pixel to its neighbour on the sphere."""
    b, c, h, w = x.shape
    out = torch.empty(b, c, h + 2 * p, w + 2 * p, dtype=x.dtype)
    for i in range(-p, h + p):
        for j in range(-p, w + p):
            ii, jj = i, j
            if ii < 0:           # across the north pole: mirrored row, half a turn away
                ii, jj = -ii - 1, jj + w // 2
            elif ii >= h:        # across the south pole
                ii, jj = 2 * h - ii - 1, jj + w // 2
            out[:, :, i + p, j + p] = x[:, :, ii, jj % w]
    return out


@pytest.mark.parametrize("p", [1, 2, 3])
def test_spherical_pad_matches_slow_reference(p):
    x = torch.randn(2, 3, 6, 12)
    assert torch.equal(spherical_pad(x, p), slow_spherical_pad(x, p))


@pytest.mark.parametrize("p", [1, 2, 3])
@pytest.mark.parametrize("h", [3, 6])
def test_spherical_pad_gradient_equals_autograd_through_the_slow_reference(p, h):
    """The hand-written adjoint against autograd through the per-pixel reference, and
    torch.autograd.gradcheck (finite differences) in float64."""
    x = torch.randn(2, 3, h, 2 * h + 2 * (h % 2), dtype=torch.float64, requires_grad=True)
    w = torch.randn(2, 3, x.shape[2] + 2 * p, x.shape[3] + 2 * p, dtype=torch.float64)
    (g,) = torch.autograd.grad((spherical_pad(x, p) * w).sum(), x)
    (g_ref,) = torch.autograd.grad((slow_spherical_pad(x, p) * w).sum(), x)
    torch.testing.assert_close(g, g_ref, rtol=0, atol=1e-12)
    assert torch.autograd.gradcheck(lambda t: spherical_pad(t, p), (x[:1, :1].detach().requires_grad_(),))


@pytest.mark.parametrize("p", [1, 2])
def test_spherical_pad_with_fused_silu_equals_padding_the_activation(p):
    x = torch.randn(2, 3, 6, 12, dtype=torch.float64, requires_grad=True)
    ref = slow_spherical_pad(torch.nn.functional.silu(x), p)
    with torch.no_grad():  # the fused path writes SiLU straight into the padded buffer
        torch.testing.assert_close(spherical_pad(x, p, silu=True), ref.detach(), rtol=0, atol=1e-15)
    # with autograd: same values and the gradient of the composition
    y = spherical_pad(x, p, silu=True)
    torch.testing.assert_close(y, ref, rtol=0, atol=1e-15)
    w = torch.randn_like(ref)
    (g,) = torch.autograd.grad((y * w).sum(), x)
    (g_ref,) = torch.autograd.grad((ref * w).sum(), x)
    torch.testing.assert_close(g, g_ref)


def test_padding_neighbour_across_pole_is_half_a_turn_away():
    h, w = 8, 16
    x = torch.arange(h * w, dtype=torch.float32).reshape(1, 1, h, w)
    y = spherical_pad(x, 1)
    for j in range(w):
        assert y[0, 0, 0, j + 1] == x[0, 0, 0, (j + w // 2) % w]
        assert y[0, 0, -1, j + 1] == x[0, 0, -1, (j + w // 2) % w]
    # longitude wrap
    assert torch.equal(y[0, 0, 1:-1, 0], x[0, 0, :, -1]) and torch.equal(y[0, 0, 1:-1, -1], x[0, 0, :, 0])
    # geometric check: the padded cell above row 0 lies next to it on the sphere
    d = pixel_directions(h, w, dtype=torch.float64)
    j = 3
    above = d[0, (j + w // 2) % w]        # what the padding puts above (0, j)
    # its angular distance to (0, j) is one row pitch (pi / H) through the pole
    ang = math.acos(float((above * d[0, j]).sum()))
    assert abs(ang - math.pi / h) < 1e-12


def test_sample_equirect_reproduces_pixels_and_is_seam_continuous():
    pano = torch.randn(1, 2, 8, 16, dtype=torch.float64)
    d = pixel_directions(8, 16, dtype=torch.float64)
    assert torch.allclose(sample_equirect(pano, d), pano, atol=1e-12)
    # across the seam (u = 0, looking along -z) the sampled field is continuous
    eps = 1e-7
    left = torch.tensor([[-eps, 0.2, -1.0]], dtype=torch.float64)
    right = torch.tensor([[eps, 0.2, -1.0]], dtype=torch.float64)
    assert (sample_equirect(pano, left) - sample_equirect(pano, right)).abs().max() < 1e-5
    # and across the pole
    up_a = torch.tensor([[eps, 1.0, 0.0]], dtype=torch.float64)
    up_b = torch.tensor([[-eps, 1.0, 0.0]], dtype=torch.float64)
    assert (sample_equirect(pano, up_a) - sample_equirect(pano, up_b)).abs().max() < 1e-5


def test_rotation_about_y_is_a_roll():
    pano = torch.randn(1, 3, 16, 32, dtype=torch.float64)
    k = 5
    # a light at direction a moves to R a: rotating about +y by +k pixels shifts content...
    r = rotation_matrix("y", -2 * math.pi * k / 32)
    out = rotate_panorama(pano, r)
    rolled = torch.roll(pano, k, dims=3)
    assert torch.allclose(out, rolled, atol=1e-9)


def test_rotation_moves_content_by_r():
    h, w = 64, 128
    pano = smooth_pano(h, w)
    r = rotation_matrix((0.3, 1.0, -0.2), 0.4)
    out = rotate_panorama(pano, r)
    # independent reference: evaluate the smooth function at R^T d
    d = pixel_directions(h, w, dtype=torch.float64)
    ref = smooth_fn(d @ r).permute(2, 0, 1)[None]
    assert (out - ref).abs().max() < 0.02
    back = rotate_panorama(out, r.T)
    assert (back - pano).abs().mean() < 2e-3


def test_gnomonic_cut_and_paste_back():
    h, w = 64, 128
    pano = smooth_pano(h, w)
    fwd = (0.4, -0.3, -1.0)
    view = panorama_to_perspective(pano, 96, 128, 80.0, forward=fwd)
    # the view's centre pixel looks exactly along fwd
    f = torch.tensor(fwd, dtype=torch.float64)
    f = f / f.norm()
    centre = smooth_fn(f[None])[0]
    mid = view[0, :, 47:49, 63:65].mean((1, 2))
    assert torch.allclose(mid, centre, atol=0.02)
    pasted, mask = perspective_to_panorama(view, h, 80.0, forward=fwd)
    assert 0.05 < mask.float().mean() < 0.5
    err = (pasted - pano)[..., mask]
    assert err.abs().max() < 0.05


def test_batched_rotation_matches_one_at_a_time():
    # B = H = 16 would be ambiguous if the batch dimension of the directions were guessed
    pano = torch.randn(16, 2, 16, 32, dtype=torch.float64)
    rots = torch.stack([rotation_matrix((0.1 * k, 1.0, 0.3), 0.05 * k) for k in range(16)])
    batched = rotate_panorama(pano, rots)
    for k in (0, 5, 15):
        assert torch.allclose(batched[k], rotate_panorama(pano[k:k + 1], rots[k])[0], atol=1e-12)
    shared = rotate_panorama(pano, rots[3])
    assert torch.allclose(shared[7], rotate_panorama(pano[7:8], rots[3])[0], atol=1e-12)
