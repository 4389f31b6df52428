"""The irradiance at a panorama's centre and its log loss, against closed-form values."""

from __future__ import annotations

import math

import pytest
import torch

from roomlight.core.geometry.equirect import pixel_directions
from roomlight.prior.losses.irradiance import (IRRADIANCE_NORMALS, irradiance_at_centre, irradiance_log_ratio,
                                               irradiance_loss)


def _upper_hemisphere(h=64, level=(1.0, 0.5, 0.25)):
    """(1, 3, h, 2h): radiance ``level`` over the upper hemisphere (+y), black below (rows split at the horizon)."""
    d = pixel_directions(h, 2 * h, dtype=torch.float64)
    up = (d[..., 1] > 0).double()
    return torch.stack([c * up for c in level])[None]


def test_a_uniform_panorama_gives_pi_times_its_radiance_on_every_normal():
    rad = torch.full((1, 3, 32, 64), 2.0, dtype=torch.float64)
    e = irradiance_at_centre(rad)
    assert e.shape == (1, 14, 3)
    # the pixels' solid angles are exact; the cosine is taken at pixel centres, so a 32-row grid is
    # within a fraction of a percent of the integral
    assert torch.allclose(e, torch.full_like(e, 2.0 * math.pi), rtol=5e-3)


def test_an_overcast_sky_gives_the_tilted_surface_formula():
    # a surface tilted by t from facing up receives pi L (1 + cos t) / 2 from a uniform upper hemisphere
    rad = _upper_hemisphere(128)
    e = irradiance_at_centre(rad)[0]  # (14, 3)
    cos_tilt = IRRADIANCE_NORMALS[:, 1]
    expected = math.pi * (1.0 + cos_tilt) / 2.0
    for c, level in enumerate((1.0, 0.5, 0.25)):
        assert torch.allclose(e[:, c], level * expected, rtol=5e-3, atol=2e-3)


def test_a_small_lamp_gives_its_solid_angle_times_the_cosine():
    # a cap of angular radius a around direction l: E(n) = L * 2 pi (1 - cos a) * (n . l) for n well inside
    h = 256
    d = pixel_directions(h, 2 * h, dtype=torch.float64)
    lamp = torch.tensor([0.3, 0.8, -0.52], dtype=torch.float64)
    lamp = lamp / lamp.norm()
    a = math.radians(6.0)
    cap = ((d @ lamp) > math.cos(a)).double()
    rad = torch.stack([cap * 100.0] * 3)[None]
    e = irradiance_at_centre(rad)[0, :, 0]
    cos_n = IRRADIANCE_NORMALS @ lamp
    expected = 100.0 * 2.0 * math.pi * (1.0 - math.cos(a)) * cos_n.clamp_min(0.0)
    well_inside = cos_n > math.sin(a) + 0.05
    # the cap's pixelated rim: a few percent at 256 rows
    assert torch.allclose(e[well_inside], expected[well_inside], rtol=0.04)
    assert torch.all(e[cos_n < -math.sin(a)] == 0)


def test_a_guess_twice_too_bright_costs_log_two_and_reads_one_stop():
    rad = _upper_hemisphere(32) + 0.05
    assert float(irradiance_loss(2.0 * rad, rad)) == pytest.approx(math.log(2.0), rel=1e-5)
    assert float(irradiance_log_ratio(0.5 * rad, rad)[0]) == pytest.approx(-1.0, abs=1e-5)


def test_a_smeared_lamp_keeps_its_irradiance_where_a_pixel_loss_would_not():
    # the same energy spread over a wider cap: per-pixel log errors are large, the irradiance error small
    h = 64
    d = pixel_directions(h, 2 * h, dtype=torch.float64)
    up = torch.tensor([0.0, 1.0, 0.0], dtype=torch.float64)
    from roomlight.core.geometry.equirect import pixel_solid_angles

    omega = pixel_solid_angles(h, 2 * h, dtype=torch.float64)
    base = 0.1 * torch.ones(h, 2 * h, dtype=torch.float64)
    sharp, wide = (d @ up > math.cos(math.radians(8))).double(), (d @ up > math.cos(math.radians(25))).double()
    sharp_pano = base + sharp * 50.0
    wide_pano = base + wide * 50.0 * float((sharp * omega).sum() / (wide * omega).sum())
    to_rgb = lambda p: torch.stack([p] * 3)[None]  # noqa: E731
    irr = float(irradiance_loss(to_rgb(wide_pano), to_rgb(sharp_pano)))
    pixel = float((torch.log(wide_pano) - torch.log(sharp_pano)).abs().mean())
    assert irr < pixel / 3
    # the surface facing the lamp: a uniform cap of radius a has mean cosine (1 + cos a) / 2, so the
    # lamp's share of the irradiance changes by (1 + cos 25) / (1 + cos 8) and no more
    facing = int(torch.argmax(IRRADIANCE_NORMALS @ up))
    e_wide = irradiance_at_centre(to_rgb(wide_pano))[0, facing, 0]
    e_sharp = irradiance_at_centre(to_rgb(sharp_pano))[0, facing, 0]
    lamp_share = lambda e: e - 0.1 * math.pi  # noqa: E731  (the uniform base gives pi * 0.1)
    expected = (1 + math.cos(math.radians(25))) / (1 + math.cos(math.radians(8)))
    assert float(lamp_share(e_wide) / lamp_share(e_sharp)) == pytest.approx(expected, rel=0.01)


def test_the_loss_gradient_matches_finite_differences():
    torch.manual_seed(0)
    target = torch.rand(2, 3, 6, 12, dtype=torch.float64) + 0.1
    pred = (torch.rand(2, 3, 6, 12, dtype=torch.float64) + 0.1).requires_grad_(True)
    assert torch.autograd.gradcheck(lambda p: irradiance_loss(p, target), (pred,), eps=1e-6, atol=1e-6)
