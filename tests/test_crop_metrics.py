"""The three-sphere protocol's tone mapping and scores against values worked by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from roomlight.errors import ShapeError
from roomlight.evaluation.crops.metrics import (CROP_TONEMAP, SCORE_TONEMAP, Tonemap, normalise_percentiles,
                                                sphere_angular_error, sphere_normalised_rmse, sphere_rmse,
                                                sphere_scores, sphere_si_rmse, tonemap)


def _pair():
    """Two 1 x 3 'renders' and a mask of the first two pixels.

    pixel 0: pred (1, 0, 0), truth (0, 1, 0): squared error 2, angle 90 degrees
    pixel 1: pred (1, 1, 1), truth (2, 2, 2): squared error 3, angle 0
    pixel 2 (outside the mask): anything."""
    pred = np.array([[[1.0, 0.0, 0.0], [1.0, 1.0, 1.0], [9.0, 9.0, 9.0]]])
    gt = np.array([[[0.0, 1.0, 0.0], [2.0, 2.0, 2.0], [0.0, 0.0, 0.0]]])
    mask = np.array([[True, True, False]])
    return pred, gt, mask


def test_rmse_sums_channels_and_divides_by_pixels():
    pred, gt, mask = _pair()
    assert sphere_rmse(pred, gt, mask) == pytest.approx(math.sqrt((2 + 3) / 2))


def test_si_rmse_is_the_rmse_after_the_best_single_scale():
    pred, gt, mask = _pair()
    # a = sum p^2 = 1 + 3 = 4, sum p g = 0 + 6 = 6, c = sum g^2 = 1 + 12 = 13: best s = 6 / 4 = 1.5,
    # residual 13 - 36 / 4 = 4, over 2 pixels
    assert sphere_si_rmse(pred, gt, mask) == pytest.approx(math.sqrt(4 / 2))
    assert sphere_rmse(1.5 * pred, gt, mask) == pytest.approx(math.sqrt(4 / 2))   # the same, by the scale itself
    assert sphere_si_rmse(7.0 * gt, gt, mask) == pytest.approx(0.0, abs=1e-12)     # a scaled truth scores 0
    assert sphere_si_rmse(np.zeros_like(gt), gt, mask) == pytest.approx(math.sqrt(13 / 2))


def test_angular_error_averages_per_pixel_angles_and_zero_vectors_count_nothing():
    pred, gt, mask = _pair()
    assert sphere_angular_error(pred, gt, mask) == pytest.approx(90.0 / 2)
    black = pred.copy()
    black[0, 0] = 0.0  # undefined angle: 0, as the field's code leaves it
    assert sphere_angular_error(black, gt, mask) == pytest.approx(0.0)
    # 60 degrees by construction: (1, 0, 0) against (1, sqrt 3, 0) / 2
    a = np.array([[[1.0, 0.0, 0.0]]])
    b = np.array([[[0.5, math.sqrt(3) / 2, 0.0]]])
    assert sphere_angular_error(a, b, np.array([[True]])) == pytest.approx(60.0)


def test_normalised_rmse_rescales_each_render_by_its_own_percentiles():
    x = np.linspace(0.0, 10.0, 1001).reshape(1, 1001, 1).repeat(3, axis=2)
    n = normalise_percentiles(x)
    # 3003 values, each of 0, 0.01, ..., 10 three times; linear interpolation at rank q (n - 1):
    # p_0.01 at rank 0.3 (between two zeros) = 0, p_99.9 at rank 2999.0 (the 2999th value, 9.99) = 9.99
    assert n[0, 0, 0] == pytest.approx(0.0, abs=1e-12)
    assert n[0, -1, 0] == pytest.approx(10.0 / 9.99)
    mask = np.ones((1, 1001), bool)
    assert sphere_normalised_rmse(3.0 * x + 2.0, x, mask) == pytest.approx(0.0, abs=1e-9)  # affine changes vanish
    assert set(sphere_scores(x, x, mask)) == {"rmse", "si_rmse", "angular_error", "norm_rmse"}


def test_tonemaps_map_the_chosen_percentile_of_the_non_zero_values():
    # values 0 (ignored), 1, 2^2.4 and 3^2.4: after the gamma 0, 1, 2, 3; their median (non-zero) is 2
    img = np.array([[[0.0, 1.0, 2.0 ** 2.4], [3.0 ** 2.4, 1.0, 2.0 ** 2.4]]])
    out, alpha = tonemap(img, SCORE_TONEMAP)
    assert alpha == pytest.approx(0.5 / 2.0)
    assert out.max() == pytest.approx(0.25 * 3.0, rel=1e-6)     # not clipped
    crop, alpha99 = tonemap(img, CROP_TONEMAP)
    # the 99th percentile of (1, 2, 3, 1, 2) by linear interpolation: rank 0.99 * 4 = 3.96, 2 + 0.96 = 2.96
    assert alpha99 == pytest.approx(0.9 / 2.96)
    # 200 ones and a 100 (after the gamma): the 99th percentile is 1, so alpha 0.9 and the 100 clips to 1
    bright = np.ones((1, 67, 3))
    bright[0, 0, 0] = 100.0 ** 2.4
    clipped, a = tonemap(bright, CROP_TONEMAP)
    assert a == pytest.approx(0.9) and clipped.max() == 1.0 and clipped.min() == pytest.approx(0.9)
    assert tonemap(img, Tonemap(gamma=1.0, percentile=100.0, mapping=1.0, clip=False))[0].max() == pytest.approx(1.0)


def test_mismatched_shapes_and_an_empty_mask_are_refused():
    pred, gt, mask = _pair()
    with pytest.raises(ShapeError, match="must be"):
        sphere_rmse(pred, gt[:, :2], mask)
    with pytest.raises(ShapeError, match="no pixel"):
        sphere_rmse(pred, gt, np.zeros_like(mask))
