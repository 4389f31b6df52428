"""The colour module: one luminance, one log-average, one display mapping for numpy and torch."""

import numpy as np
import pytest
import torch

from roomlight.core.color import (DISPLAY_GAMMA, LOG_EPS, MIDDLE_GREY, display_to_linear, display_to_uint8,
                             log_average_np, log_average_torch, luminance_np, luminance_torch, to_display,
                             to_display_at_key)


def test_luminance_numpy_and_torch_agree_and_use_rec709():
    rgb = np.random.default_rng(0).uniform(0, 4, (5, 6, 3))
    y = luminance_np(rgb)
    assert y.shape == (5, 6)
    assert y[0, 0] == pytest.approx(0.2126 * rgb[0, 0, 0] + 0.7152 * rgb[0, 0, 1] + 0.0722 * rgb[0, 0, 2])
    t = torch.from_numpy(rgb).permute(2, 0, 1)[None]  # (1, 3, H, W)
    assert torch.allclose(luminance_torch(t)[0], torch.from_numpy(y))
    assert luminance_torch(t, keepdim=True).shape == (1, 1, 5, 6)
    with pytest.raises(ValueError):
        luminance_np(rgb[..., :2])


def test_log_average_numpy_and_torch_agree():
    rgb = np.random.default_rng(1).uniform(0, 4, (4, 8, 3))
    expected = float(np.exp(np.mean(np.log(luminance_np(rgb) + LOG_EPS))))
    assert log_average_np(rgb) == pytest.approx(expected)
    t = torch.from_numpy(rgb).permute(2, 0, 1)[None]
    assert float(log_average_torch(t)[0]) == pytest.approx(expected)
    mask = np.zeros((4, 8), bool)
    mask[0, 0] = True
    assert log_average_np(rgb, mask) == pytest.approx(float(luminance_np(rgb[0, 0])) + LOG_EPS)


def test_display_mappings():
    x = np.array([-1.0, 0.0, MIDDLE_GREY, 1.0, 5.0, np.nan, np.inf])
    d = to_display(x)
    assert d == pytest.approx([0, 0, MIDDLE_GREY ** (1 / DISPLAY_GAMMA), 1, 1, 0, 1])
    assert display_to_linear(d[2]) == pytest.approx(MIDDLE_GREY)
    assert display_to_uint8(np.array([0.0, 0.5, 1.0])).tolist() == [0, 128, 255]
    flat = torch.full((1, 3, 2, 4), 7.0)  # luminance 7 everywhere: auto-exposed to middle grey
    assert torch.allclose(to_display_at_key(flat), torch.full_like(flat, MIDDLE_GREY ** (1 / DISPLAY_GAMMA)))
    assert display_to_uint8(to_display_at_key(flat)[0]).shape == (2, 4, 3)
