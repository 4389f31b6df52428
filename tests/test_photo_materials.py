"""The objects' materials of a photo fit: the reflectance prior against its formula worked by hand and
against finite differences, the metals' exemption, and the settings that refuse it."""

from __future__ import annotations

import math
import re

import pytest
import torch


def _materials(albedos, metallics):
    from roomlight.fitting.photo import ObjectMaterials

    m = ObjectMaterials(list(range(1, len(albedos) + 1)))
    for label, (a, metal) in enumerate(zip(albedos, metallics), start=1):
        m.set_values(label, albedo=a, roughness=0.5, metallic=metal)
    return m


def test_albedo_prior_is_the_log_normal_penalty_on_mean_albedo_worked_by_hand():
    """Three objects against a typical albedo of 0.3: twice as bright (ln 2 squared), exactly typical
    on average with a strong colour (0: colour is free), and a metal (exempt). The geometric mean of
    (0.15, 0.30, 0.60) is 0.3, the arithmetic mean of (0.15, 0.30, 0.45) too."""
    for average, coloured in (("geometric", (0.15, 0.30, 0.60)), ("arithmetic", (0.15, 0.30, 0.45))):
        m = _materials([(0.6, 0.6, 0.6), coloured, (0.9, 0.9, 0.9)], [0.0, 0.0, 1.0])
        value = float(m.albedo_prior(0.3, average).detach())
        # sigmoid(logit(x)) round-trips to ~1e-7; metallic 1 is stored as 1 - 1e-6, so the metal adds ~1e-6 * ln(3)^2
        assert value == pytest.approx(math.log(2.0) ** 2 / 3, abs=1e-5), average
        one = _materials([(0.1, 0.1, 0.1)], [0.0]).albedo_prior(0.3, average)
        assert float(one.detach()) == pytest.approx(math.log(3.0) ** 2, rel=1e-5)
        assert float(_materials([(0.5, 0.5, 0.5)], [0.5]).albedo_prior(0.5, average).detach()) == pytest.approx(0.0, abs=1e-9)
    # the two means differ on a coloured object: geometric (0.1 * 0.2 * 0.4)^(1/3) = 0.2, arithmetic 0.7 / 3
    m = _materials([(0.1, 0.2, 0.4)], [0.0])
    assert float(m.albedo_prior(0.3, "geometric").detach()) == pytest.approx(math.log(0.2 / 0.3) ** 2, rel=1e-5)
    assert float(m.albedo_prior(0.3, "arithmetic").detach()) == pytest.approx(math.log(0.7 / 0.9) ** 2, rel=1e-5)


@pytest.mark.parametrize("average", ["geometric", "arithmetic"])
def test_albedo_prior_gradient_matches_finite_differences_and_leaves_metallic_alone(average):
    m = _materials([(0.7, 0.2, 0.4), (0.05, 0.1, 0.08)], [0.3, 0.0])
    m.logits.data = m.logits.data.double()
    m.logits.grad = None
    m.albedo_prior(0.3, average).backward()
    grad = m.logits.grad.clone()
    eps = 1e-6
    for k in range(2):
        for c in range(3):
            with torch.no_grad():
                m.logits[k, c] += eps
                up = float(m.albedo_prior(0.3, average).detach())
                m.logits[k, c] -= 2 * eps
                down = float(m.albedo_prior(0.3, average).detach())
                m.logits[k, c] += eps
            assert float(grad[k, c]) == pytest.approx((up - down) / (2 * eps), rel=1e-5, abs=1e-9)
    # the metallic value only weights the term; making an object metallic is no way out of it
    assert float(grad[:, 4].abs().max()) == 0.0
    assert float(grad[:, 3].abs().max()) == 0.0   # roughness plays no part


def test_geometric_albedo_prior_never_tints_and_ignores_a_neutral_white_balance():
    """The geometric mean is unchanged when the channels are scaled by gains whose product is 1 (the
    white balance's exp(c) with sum(c) = 0 moved from the light into the albedo), and its gradient with
    respect to ln(albedo) is the same on every channel: it scales an object, it cannot tint it. The
    arithmetic mean fails both (yet measured better on the photo benchmark: docs/photo.md)."""
    base = (0.2, 0.35, 0.5)
    gains = (1.6, 1.0, 1.0 / 1.6)
    tinted = tuple(a * g for a, g in zip(base, gains))
    for average, invariant in (("geometric", True), ("arithmetic", False)):
        a = float(_materials([base], [0.0]).albedo_prior(0.3, average).detach())
        b = float(_materials([tinted], [0.0]).albedo_prior(0.3, average).detach())
        assert (a == pytest.approx(b, rel=1e-5)) is invariant, average
        m = _materials([base], [0.0])
        m.logits.data = m.logits.data.double()
        m.albedo_prior(0.3, average).backward()
        albedo = torch.sigmoid(m.logits.detach()[0, :3])
        # d/d ln(a_c) = d/d logit_c / (d ln(a_c) / d logit_c) = grad_c / (1 - a_c)
        per_log_albedo = m.logits.grad[0, :3] / (1.0 - albedo)
        spread = float(per_log_albedo.max() - per_log_albedo.min()) / float(per_log_albedo.abs().max())
        assert (spread < 1e-9) is invariant, (average, spread)


def test_photo_model_adds_the_weighted_prior_to_the_light_regularizers():
    from roomlight.fitting.inverse.lights import LightModel
    from roomlight.fitting.photo.fitter import PhotoModel

    class Bare(LightModel):
        kind = "envmap"

        def regularizers(self):
            return {"z_prior": torch.tensor(0.25)}

    m = _materials([(0.6, 0.6, 0.6)], [0.0])
    terms = PhotoModel(Bare(), m, albedo_prior=0.5, albedo_prior_mean=0.3).regularizers()
    assert set(terms) == {"z_prior", "albedo_prior"}
    assert float(terms["albedo_prior"].detach()) == pytest.approx(0.5 * math.log(2.0) ** 2, rel=1e-5)
    assert set(PhotoModel(Bare(), m, albedo_prior=0.0).regularizers()) == {"z_prior"}


@pytest.mark.parametrize("field, value, message", [
    ("albedo_prior", -0.1, "albedo_prior must be >= 0"),
    ("albedo_prior_mean", 0.0, "albedo_prior_mean must be in (0, 1)"),
    ("albedo_prior_mean", 1.0, "albedo_prior_mean must be in (0, 1)"),
    ("albedo_prior_average", "median", "albedo_prior_average must be geometric or arithmetic"),
    ("metal_band", -1.0, "metal_band must be >= 0"),
    ("metal_band_range", (0.5, 0.2), "metal_band_range must be [lo, hi] with 0 < lo < hi < 1"),
])
def test_bad_prior_settings_are_refused(field, value, message):
    from roomlight.errors import RoomlightError
    from roomlight.fitting.photo import photo_config

    with pytest.raises(RoomlightError, match=re.escape(message)):
        photo_config("fast", **{field: value}).validate()


def test_photo_fits_use_the_scalar_exposure_by_default_and_synthetic_fits_the_white_balance():
    """The white balance measured worse on photographs (docs/results.md#white-balance) and stays on for
    `roomlight fit`; every photo preset inherits the photo default, and --set can turn it back on."""
    from roomlight.fitting.inverse.config import FitConfig
    from roomlight.fitting.photo import PHOTO_PRESETS, photo_config

    assert FitConfig().white_balance is True
    assert all(cfg.white_balance is False for cfg in PHOTO_PRESETS.values())
    assert photo_config("fast", white_balance=True).white_balance is True


def test_an_albedo_range_holds_every_albedo_inside_it_and_starts_at_half():
    """albedo = lo + (hi - lo) sigmoid(x): 0.5 at the start, never outside [lo, hi] whatever x, the
    roughness and metallic untouched, a set value read back, and the gradient of the mapping by hand."""
    from roomlight.fitting.photo import ObjectMaterials

    m = ObjectMaterials([1, 2], albedo_range=(0.03, 0.9))
    assert torch.allclose(m.values(), torch.full((2, 5), 0.5), atol=1e-6)
    with torch.no_grad():
        m.logits[0, :3] = torch.tensor([-40.0, 0.0, 40.0])
    v = m.values()[0]
    assert float(v[0]) == pytest.approx(0.03, abs=1e-6) and float(v[2]) == pytest.approx(0.9, abs=1e-6)
    assert float(v[1]) == pytest.approx(0.03 + 0.87 * 0.5, abs=1e-6) and float(v[3]) == pytest.approx(0.5)
    m.set_values(2, albedo=(0.05, 0.3, 0.85), roughness=0.2)
    assert m.values()[1, :4].tolist() == pytest.approx([0.05, 0.3, 0.85, 0.2], abs=1e-5)
    m.set_values(2, albedo=(0.0, 0.5, 1.0))      # outside: held at the bounds
    assert m.values()[1, [0, 2]].tolist() == pytest.approx([0.03, 0.9], abs=1e-5)
    # d albedo / dx = (hi - lo) s (1 - s): 0.87 / 4 at x = 0
    with torch.no_grad():
        m.logits[1, 1] = 0.0
    m.logits.grad = None
    m.values()[1, 1].backward()
    assert float(m.logits.grad[1, 1]) == pytest.approx(0.87 / 4, rel=1e-6)
    # the full range is the paper's parametrisation, bit for bit
    plain, full = ObjectMaterials([1]), ObjectMaterials([1], albedo_range=(0.0, 1.0))
    assert torch.equal(plain.values(), full.values()) and not full.bounded
    with pytest.raises(Exception, match="albedo_range"):
        ObjectMaterials([1], albedo_range=(0.6, 0.9))


def test_the_metal_band_penalises_only_metals_between_a_clear_coat_and_a_real_metal():
    """Worked by hand with the band (0.06, 0.45): a metal of mean albedo 0.2 is ln(0.2/0.06) from the
    lower edge and ln(0.45/0.2) from the upper one, the shorter counts; a half-metallic object counts
    half; a dielectric, a metal at 0.03 (a black glossy surface) and one at 0.9 (silver) count nothing."""
    inside = min(math.log(0.2 / 0.06), math.log(0.45 / 0.2))
    m = _materials([(0.2, 0.2, 0.2), (0.1, 0.2, 0.3), (0.2, 0.2, 0.2), (0.03, 0.03, 0.03), (0.9, 0.9, 0.9)],
                   [1.0, 0.5, 0.0, 1.0, 1.0])
    value = float(m.metal_band_term((0.06, 0.45)).detach())
    # metallic 1 is stored as 1 - 1e-6 and 0 as 1e-6
    assert value == pytest.approx((inside ** 2 + 0.5 * inside ** 2) / 5, rel=1e-5)
    assert float(_materials([(0.3, 0.3, 0.3)], [1.0]).metal_band_term((0.06, 0.45)).detach()) == \
        pytest.approx(math.log(0.45 / 0.3) ** 2, rel=1e-5)


def test_the_metal_band_gradient_matches_finite_differences_and_reaches_the_metallic_value():
    m = _materials([(0.15, 0.25, 0.2), (0.5, 0.4, 0.42), (0.08, 0.05, 0.06)], [0.8, 0.6, 0.9])
    m.logits.data = m.logits.data.double()
    m.metal_band_term((0.06, 0.45)).backward()
    grad = m.logits.grad.clone()
    eps = 1e-6
    for k in range(3):
        for c in (0, 1, 2, 4):
            with torch.no_grad():
                m.logits[k, c] += eps
                up = float(m.metal_band_term((0.06, 0.45)).detach())
                m.logits[k, c] -= 2 * eps
                down = float(m.metal_band_term((0.06, 0.45)).detach())
                m.logits[k, c] += eps
            assert float(grad[k, c]) == pytest.approx((up - down) / (2 * eps), rel=1e-5, abs=1e-9)
    # the first (mean 0.2, nearer 0.45 in log) is pushed up, and towards a dielectric
    assert float(grad[0, :3].sum()) < 0 and float(grad[0, 4]) > 0
    assert float(grad[:, 3].abs().max()) == 0.0   # roughness plays no part


def test_photo_model_adds_the_metal_band_only_when_asked():
    from roomlight.fitting.inverse.lights import LightModel
    from roomlight.fitting.photo.fitter import PhotoModel

    class Bare(LightModel):
        kind = "envmap"

        def regularizers(self):
            return {}

    m = _materials([(0.3, 0.3, 0.3)], [1.0])
    terms = PhotoModel(Bare(), m, metal_band=2.0, metal_band_range=(0.06, 0.45)).regularizers()
    assert float(terms["metal_band"].detach()) == pytest.approx(2.0 * math.log(0.45 / 0.3) ** 2, rel=1e-5)
    assert "metal_band" not in PhotoModel(Bare(), m).regularizers()
