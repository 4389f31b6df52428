"""The latent anchor of the prior methods: a pull 0.5 w |z - z_start|^2 towards where the fit started.

Its value is the formula's, computed by hand; its gradient is w (z - z_start), checked against finite
differences; it is absent at weight 0 (a photo fit anchors at its own start: tests/test_photo_fit.py)."""

from __future__ import annotations

import pytest
import torch

from helpers_prior import tiny_prior
from roomlight.errors import RoomlightError
from roomlight.fitting.inverse.lights import PriorLight

pytestmark = pytest.mark.usefixtures("one_torch_thread")


def test_anchor_value_and_gradient_against_finite_differences():
    light = PriorLight(tiny_prior(), z_anchor=0.3)
    n = light.z.numel()
    g = torch.Generator().manual_seed(1)
    start = torch.randn(n, generator=g)
    with torch.no_grad():
        light.z.copy_(start)
    light.anchor_here()
    moved = start + 0.1 * torch.randn(n, generator=g)
    with torch.no_grad():
        light.z.copy_(moved)
    by_hand = 0.3 * 0.5 * sum(float(a - b) ** 2 for a, b in zip(moved, start))
    term = light.regularizers()["z_anchor"]
    assert float(term) == pytest.approx(by_hand, rel=1e-5)
    term.backward()
    eps = 1e-2
    for k in (0, n // 2, n - 1):
        values = []
        for sign in (1, -1):
            with torch.no_grad():
                light.z[k] += sign * eps
            values.append(float(light.regularizers()["z_anchor"]))
            with torch.no_grad():
                light.z[k] -= sign * eps
        assert float(light.z.grad[k]) == pytest.approx((values[0] - values[1]) / (2 * eps), rel=1e-3, abs=1e-6)
    # moving the anchor itself is no part of the fit: the start carries no gradient
    assert not light.z_start.requires_grad
    # the record says how far z went from its start: the Euclidean distance, summed by hand
    travel = sum(float(a - b) ** 2 for a, b in zip(moved, start)) ** 0.5
    assert light.describe()["z_travel"] == pytest.approx(travel, rel=1e-5)


def test_an_unanchored_light_records_no_travel():
    assert "z_travel" not in PriorLight(tiny_prior()).describe()


def test_no_anchor_term_at_weight_zero_and_negative_weights_are_refused():
    assert "z_anchor" not in PriorLight(tiny_prior()).regularizers()
    with pytest.raises(ValueError):
        PriorLight(tiny_prior(), z_anchor=-1.0)
    from roomlight.fitting.photo.config import photo_config

    with pytest.raises(RoomlightError, match="z_anchor"):
        photo_config("fast", z_anchor=-0.1)

