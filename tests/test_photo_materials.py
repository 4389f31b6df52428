"""The objects' materials of a photo fit: the reflectance prior against its formula worked by hand and
against finite differences, the metals' exemption, and the settings that refuse it."""

from __future__ import annotations

import math

import pytest
import torch


def _materials(albedos, metallics):
    from roomlight.photo import ObjectMaterials

    m = ObjectMaterials(list(range(1, len(albedos) + 1)))
    for label, (a, metal) in enumerate(zip(albedos, metallics), start=1):
        m.set_values(label, albedo=a, roughness=0.5, metallic=metal)
    return m


def test_albedo_prior_is_the_log_normal_penalty_on_mean_albedo_worked_by_hand():
    """Three objects against a typical albedo of 0.3: twice as bright (ln 2 squared), exactly typical
    on average with a strong colour (0: colour is free), and a metal (exempt)."""
    m = _materials([(0.6, 0.6, 0.6), (0.15, 0.30, 0.45), (0.9, 0.9, 0.9)], [0.0, 0.0, 1.0])
    value = float(m.albedo_prior(0.3).detach())
    # sigmoid(logit(x)) round-trips to ~1e-7; metallic 1 is stored as 1 - 1e-6, so the metal adds ~1e-6 * ln(3)^2
    assert value == pytest.approx(math.log(2.0) ** 2 / 3, abs=1e-5)
    assert float(_materials([(0.1, 0.1, 0.1)], [0.0]).albedo_prior(0.3).detach()) == pytest.approx(math.log(3.0) ** 2, rel=1e-5)
    assert float(_materials([(0.5, 0.5, 0.5)], [0.5]).albedo_prior(0.5).detach()) == pytest.approx(0.0, abs=1e-9)


def test_albedo_prior_gradient_matches_finite_differences_and_leaves_metallic_alone():
    m = _materials([(0.7, 0.2, 0.4), (0.05, 0.1, 0.08)], [0.3, 0.0])
    m.logits.data = m.logits.data.double()
    m.logits.grad = None
    m.albedo_prior(0.3).backward()
    grad = m.logits.grad.clone()
    eps = 1e-6
    for k in range(2):
        for c in range(3):
            with torch.no_grad():
                m.logits[k, c] += eps
                up = float(m.albedo_prior(0.3).detach())
                m.logits[k, c] -= 2 * eps
                down = float(m.albedo_prior(0.3).detach())
                m.logits[k, c] += eps
            assert float(grad[k, c]) == pytest.approx((up - down) / (2 * eps), rel=1e-5, abs=1e-9)
    # the metallic value only weights the term; making an object metallic is no way out of it
    assert float(grad[:, 4].abs().max()) == 0.0
    assert float(grad[:, 3].abs().max()) == 0.0   # roughness plays no part


def test_photo_model_adds_the_weighted_prior_to_the_light_regularizers():
    from roomlight.inverse.lights import LightModel
    from roomlight.photo.fitter import PhotoModel

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
])
def test_bad_prior_settings_are_refused(field, value, message):
    from roomlight.errors import RoomlightError
    from roomlight.photo import photo_config

    with pytest.raises(RoomlightError, match=message.replace("(", r"\(").replace(")", r"\)")):
        photo_config("fast", **{field: value}).validate()
