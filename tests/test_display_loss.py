"""The display loss: its value is the PSNR LDR metric's error, its gradient reaches every pixel it should."""

from __future__ import annotations

import math

import pytest
import torch

from roomlight.prior.losses.display import display_loss


def _pair(seed=0, b=2, h=8, w=16):
    g = torch.Generator().manual_seed(seed)
    target = torch.exp(torch.randn(b, 3, h, w, generator=g, dtype=torch.float64))
    target[:, :, 0, :3] = 200.0                      # a lamp that clips
    pred = target * torch.exp(0.3 * torch.randn(b, 3, h, w, generator=g, dtype=torch.float64))
    return pred, target


def test_the_value_is_the_mean_squared_error_the_psnr_ldr_metric_reads():
    from roomlight.prior.eval.metrics import psnr, to_ldr

    pred, target = _pair()
    loss = float(display_loss(pred, target))
    # per image PSNR -> MSE, averaged: images of one size weigh equally
    mse = (10.0 ** (-psnr(to_ldr(pred, target), to_ldr(target)) / 10.0)).mean()
    assert loss == pytest.approx(float(mse), rel=1e-9)


def test_the_value_by_hand_for_one_pixel_pair():
    # a flat target: its log-average is its own value, exposed to middle grey
    target = torch.full((1, 3, 2, 2), 2.0, dtype=torch.float64)
    pred = target.clone()
    pred[0, :, 0, 0] = 4.0                           # twice as bright: 0.36 on display before gamma
    expected = ((0.36 ** (1 / 2.2) - 0.18 ** (1 / 2.2)) ** 2) / 4
    assert float(display_loss(pred, target)) == pytest.approx(expected, rel=1e-6)


def test_the_gradient_matches_finite_differences_below_the_clip():
    pred, target = _pair(seed=1)
    pred = pred.clone().requires_grad_(True)
    display_loss(pred, target).backward()
    y = 0.2126 * target[:, 0] + 0.7152 * target[:, 1] + 0.0722 * target[:, 2]
    k = [0.18 / math.exp(float(torch.log(y[b] + 1e-6).mean())) for b in range(2)]
    checked = 0
    for idx in [(0, 0, 3, 5), (0, 2, 6, 1), (1, 1, 4, 9), (1, 0, 7, 15), (0, 1, 2, 8)]:
        if max(float(pred.detach()[idx]), float(target[idx])) * k[idx[0]] >= 1:
            continue
        checked += 1
        eps = 1e-6 * float(pred.detach()[idx])
        up, down = pred.detach().clone(), pred.detach().clone()
        up[idx] += eps
        down[idx] -= eps
        fd = (float(display_loss(up, target)) - float(display_loss(down, target))) / (2 * eps)
        assert float(pred.grad[idx]) == pytest.approx(fd, rel=1e-4, abs=1e-12)
    assert checked >= 3


def test_an_over_exposed_guess_is_pulled_down_where_the_target_does_not_clip_and_left_where_it_does():
    target = torch.full((1, 3, 2, 2), 1.0, dtype=torch.float64)
    target[0, :, 0, 0] = 1000.0                      # a lamp: clips at any exposure here
    pred = target.clone()
    pred[0, :, 1, 1] = 1000.0                        # a lamp where the room has a wall
    pred.requires_grad_(True)
    display_loss(pred, target).backward()
    assert (pred.grad[0, :, 1, 1] > 0).all()         # descending lowers it
    # its size: d/dp of (D - d_t)^2 / N with D's slope at the clip, 1 / 2.2, times the exposure k
    k = 0.18 / math.exp(math.log(1.0 + 1e-6) * 3 / 4 + math.log(1000.0 + 1e-6) / 4)
    d_t = (k * 1.0) ** (1 / 2.2)
    expected = 2 * (1.0 - d_t) * (1 / 2.2) * k / 12
    assert pred.grad[0, :, 1, 1].tolist() == pytest.approx([expected] * 3, rel=1e-6)
    assert (pred.grad[0, :, 0, 0] == 0).all()        # both clip: nothing to learn
    assert torch.isfinite(pred.grad).all()


def test_an_image_without_its_batch_axis_is_refused():
    from roomlight.errors import ShapeError

    with pytest.raises(ShapeError, match="B, 3, H, W"):
        display_loss(torch.ones(3, 4, 8), torch.ones(3, 4, 8))


def test_a_black_guess_has_a_finite_gradient_towards_the_target():
    target = torch.full((1, 3, 2, 2), 1.0, dtype=torch.float64)
    pred = target.clone()
    pred[0, :, 0, 1] = 0.0
    pred.requires_grad_(True)
    display_loss(pred, target).backward()
    assert torch.isfinite(pred.grad).all() and (pred.grad[0, :, 0, 1] < 0).all()
