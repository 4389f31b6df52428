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


def _two_hemispheres(h, upper, lower):
    """(1, 3, h, 2h) grey radiance ``upper`` above the horizon and ``lower`` below it, and the (1, h, 2h)
    mask of the lower hemisphere (the part a downward view would see)."""
    d = pixel_directions(h, 2 * h, dtype=torch.float64)
    up = (d[..., 1] > 0).double()
    rad = upper * up + lower * (1.0 - up)
    return torch.stack([rad] * 3)[None], (up == 0)[None]


def test_seen_matching_leaves_only_the_unseen_parts_energy_relative_to_the_seen_part():
    from roomlight.prior.losses.irradiance import seen_matched

    # truth: ceiling 1, floor 0.5; the view sees the floor. The guess is 7x too bright overall and its
    # ceiling is twice the truth's relative to its floor: after matching, floor 0.5 and ceiling 2.
    target, floor = _two_hemispheres(128, 1.0, 0.5)
    guess, _ = _two_hemispheres(128, 7.0 * 2.0, 7.0 * 0.5)
    matched = seen_matched(guess, target, floor)
    assert torch.allclose(matched[0, :, floor[0]], torch.full_like(matched[0, :, floor[0]], 0.5))
    assert torch.allclose(matched[0, :, ~floor[0]], torch.full_like(matched[0, :, ~floor[0]], 2.0))
    # a tilted surface gets pi (L_up (1 + cos t) + L_down (1 - cos t)) / 2 (the overcast-sky formula twice)
    cos_t = IRRADIANCE_NORMALS[:, 1]
    expected = torch.log2((2.0 * (1 + cos_t) + 0.5 * (1 - cos_t)) / (1.0 * (1 + cos_t) + 0.5 * (1 - cos_t))).mean()
    assert float(irradiance_log_ratio(guess, target, seen=floor)[0]) == pytest.approx(float(expected), abs=5e-3)
    # without the matching the overall factor 7 dominates
    assert float(irradiance_log_ratio(guess, target)[0]) > float(expected) + 2.5


def test_the_seen_matched_loss_is_blind_to_the_guesss_overall_level_and_its_gradient_too():
    torch.manual_seed(0)
    target = torch.rand(2, 3, 16, 32, dtype=torch.float64) + 0.05
    guess = torch.rand(2, 3, 16, 32, dtype=torch.float64) + 0.05
    seen = torch.zeros(2, 16, 32, dtype=torch.bool)
    seen[0, 8:, :10], seen[1, 4:12, 5:20] = True, True
    base = float(irradiance_loss(guess, target, seen=seen))
    # (exactly blind but for the 1e-6 added to the luminance before its log: luminances here are >= 0.05)
    assert float(irradiance_loss(5.0 * guess, target, seen=seen)) == pytest.approx(base, rel=1e-4)
    alpha = torch.tensor(1.0, dtype=torch.float64, requires_grad=True)
    irradiance_loss(alpha * guess, target, seen=seen).backward()
    assert abs(float(alpha.grad)) < 1e-4
    # a guess equal to the truth up to a factor costs nothing
    assert float(irradiance_loss(0.3 * target, target, seen=seen)) == pytest.approx(0.0, abs=1e-4)
    # and the gradient in the guess's pixels agrees with finite differences
    g = guess[:1, :, ::4, ::4].clone().requires_grad_(True)
    t, m = target[:1, :, ::4, ::4], seen[:1, ::4, ::4]
    assert torch.autograd.gradcheck(lambda x: irradiance_loss(x, t, seen=m), (g,), eps=1e-6, atol=1e-6)


def test_seen_matching_agrees_with_the_photo_fits_exposure_match_on_cells_of_equal_solid_angle():
    from roomlight.core.geometry.equirect import pixel_directions as dirs_of
    from roomlight.fitting.photo.placement import matching_log_exposure
    from roomlight.prior.losses.irradiance import seen_matched

    torch.manual_seed(3)
    h, w = 16, 32
    target = 0.05 + 0.9 * torch.rand(1, 3, h, w, dtype=torch.float64)
    guess = 0.02 + 3.0 * torch.rand(1, 3, h, w, dtype=torch.float64)
    seen = torch.zeros(1, h, w, dtype=torch.bool)
    seen[0, 11, 3:25] = True  # one row: every cell the same solid angle
    factor = float((seen_matched(guess, target, seen) / guess)[0, 0, 0, 0])
    d = dirs_of(h, w, dtype=torch.float64)[seen[0]]
    observed = target[0].permute(1, 2, 0)[seen[0]].numpy()
    log_k = matching_log_exposure(guess[0].permute(1, 2, 0).float(), d.numpy(), observed)
    assert math.log(factor) == pytest.approx(log_k, abs=2e-3)


def test_a_panorama_with_nothing_seen_is_left_as_is_and_a_wrong_mask_is_refused():
    from roomlight.errors import ShapeError
    from roomlight.prior.losses.irradiance import seen_matched

    guess, target = torch.rand(1, 3, 8, 16) + 0.1, torch.rand(1, 3, 8, 16) + 0.1
    assert torch.equal(seen_matched(guess, target, torch.zeros(1, 8, 16, dtype=torch.bool)), guess)
    with pytest.raises(ShapeError, match="mask"):
        seen_matched(guess, target, torch.zeros(1, 8, 8, dtype=torch.bool))
