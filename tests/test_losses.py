"""Tests of the training losses (roomlight.prior.losses) against hand-computed values and slow loops."""

from __future__ import annotations

import math

import pytest
import torch

from roomlight.errors import ShapeError
from roomlight.prior.losses import (
    LossConfig,
    gradient_loss,
    kl_divergence,
    kl_weight,
    l1_loss,
    peak_loss,
    peak_mask,
    scharr_gradients,
    top_fraction_mask,
    vae_loss,
)
from roomlight.prior.model import Normalization


pytestmark = pytest.mark.usefixtures("one_torch_thread")


SCHARR = [[-3, 0, 3], [-10, 0, 10], [-3, 0, 3]]


def padded_value(x: torch.Tensor, i: int, j: int) -> torch.Tensor:
    """x (C, H, W) at (i, j) in [-1, H] x [-1, W] with spherical padding, by the definition."""
    _, h, w = x.shape
    if i < 0 or i >= h:
        i = -1 - i if i < 0 else 2 * h - 1 - i
        j = j + w // 2
    return x[:, i, j % w]


def slow_scharr(x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """Explicit loop: grad_u(i, j) = sum_ab K[a][b] x(i+a-1, j+b-1) / 32, K^T for grad_v."""
    c, h, w = x.shape
    gu = torch.zeros(c, h, w, dtype=x.dtype)
    gv = torch.zeros(c, h, w, dtype=x.dtype)
    for i in range(h):
        for j in range(w):
            for a in range(3):
                for b in range(3):
                    p = padded_value(x, i + a - 1, j + b - 1)
                    gu[:, i, j] += SCHARR[a][b] / 32 * p
                    gv[:, i, j] += SCHARR[b][a] / 32 * p
    return gu, gv


# ----------------------------------------------------------------------------- L1
def test_l1_hand_value():
    pred = torch.tensor([[1.0, -2.0], [3.0, 0.5]])
    target = torch.tensor([[0.0, 0.0], [1.0, 0.5]])
    assert l1_loss(pred, target).item() == pytest.approx((1 + 2 + 2 + 0) / 4)
    with pytest.raises(ShapeError, match="must have the same shape"):
        l1_loss(pred, target[:1])


# ----------------------------------------------------------------------------- Scharr
def test_scharr_on_ramps_by_hand():
    # x(i, j) = j on a 4 x 8 map: slope 1 inside, and across the seam the wrap sees 7 -> 0.
    ramp_u = torch.arange(8.0).expand(1, 1, 4, 8)
    gu, gv = scharr_gradients(ramp_u)
    # Inner rows: (3 + 10 + 3) * (x(j+1) - x(j-1)) / 32 = 16 * 2 / 32 = 1, and at the seam
    # columns 16 * (1 - 7) / 32 = -3.
    inner = torch.tensor([-3.0, 1, 1, 1, 1, 1, 1, -3])
    torch.testing.assert_close(gu[0, 0, 1:3], inner.expand(2, 8))
    # Rows 0 and 3: the 3-weighted neighbour row lies beyond the pole, i.e. is this row rolled
    # by 4 columns (values j + 4 mod 8), whose central difference is -6 at j = 3, 4 and 2
    # elsewhere; the 13-weighted part (own row + the other neighbour) is 2, or -6 at the seam.
    # j=0: (3*2 + 13*(-6))/32 = -2.25; j=3, 4: (3*(-6) + 13*2)/32 = 0.25; else 32/32 = 1.
    pole = torch.tensor([-2.25, 1, 1, 0.25, 0.25, 1, 1, -2.25])
    torch.testing.assert_close(gu[0, 0, 0], pole)
    torch.testing.assert_close(gu[0, 0, 3], pole)
    # grad_v of a function of j only: rows beyond the poles come from column j + 4, so the
    # vertical difference there is x(j) - x(j + 4 mod 8), weighted by the row of +/-3, 10, 3.
    # Row 0: (x(1, .) - padded(-1, .)) smoothed along u, where padded(-1, j) = j + 4 mod 8.
    x0 = torch.arange(8.0)
    up = (x0 + 4) % 8
    d = x0 - up  # row 1 minus padded row -1, per column
    expected_v0 = torch.stack([(3 * d[(j - 1) % 8] + 10 * d[j] + 3 * d[(j + 1) % 8]) / 32
                               for j in range(8)])
    torch.testing.assert_close(gv[0, 0, 0], expected_v0)
    torch.testing.assert_close(gv[0, 0, 1:3], torch.zeros(2, 8))
    # x(i, j) = i: slope 1 inside; at the top the padded row equals row 0, so (1 - 0) * 16/32.
    ramp_v = torch.arange(4.0)[:, None].expand(1, 1, 4, 8)
    gu, gv = scharr_gradients(ramp_v)
    torch.testing.assert_close(gu, torch.zeros_like(gu))
    torch.testing.assert_close(gv[0, 0, :, 0], torch.tensor([0.5, 1.0, 1.0, 0.5]))


def test_scharr_matches_slow_loop():
    x = torch.randn(2, 3, 4, 8, dtype=torch.float64, generator=torch.Generator().manual_seed(0))
    gu, gv = scharr_gradients(x)
    for b in range(2):
        ru, rv = slow_scharr(x[b])
        torch.testing.assert_close(gu[b], ru)
        torch.testing.assert_close(gv[b], rv)


def test_gradient_loss_matches_pyramid_loop():
    g = torch.Generator().manual_seed(1)
    pred = torch.randn(2, 3, 4, 8, dtype=torch.float64, generator=g)
    target = torch.randn(2, 3, 4, 8, dtype=torch.float64, generator=g)
    levels = 3  # 4x8, 2x4, 1x2
    total = 0.0
    p, t = pred, target
    for o in range(levels):
        if o:
            # 2x2 average pooling written out.
            p = p.reshape(2, 3, p.shape[2] // 2, 2, p.shape[3] // 2, 2).mean(dim=(3, 5))
            t = t.reshape(2, 3, t.shape[2] // 2, 2, t.shape[3] // 2, 2).mean(dim=(3, 5))
        diffs_u, diffs_v = [], []
        for b in range(2):
            pu, pv = slow_scharr(p[b])
            tu, tv = slow_scharr(t[b])
            diffs_u.append((pu - tu).abs())
            diffs_v.append((pv - tv).abs())
        total += torch.stack(diffs_u).mean() + torch.stack(diffs_v).mean()
    expected = total / (2 * levels)
    torch.testing.assert_close(gradient_loss(pred, target, levels=levels), expected)
    assert gradient_loss(pred, pred, levels=levels).item() == 0.0


def test_gradient_loss_is_seam_free_and_checks_shapes():
    # A map that is smooth on the sphere but has its seam in the middle after a roll has the
    # same loss as the unrolled one (no artificial edge at u = 0).
    g = torch.Generator().manual_seed(2)
    a = torch.randn(1, 1, 8, 16, generator=g)
    b = torch.randn(1, 1, 8, 16, generator=g)
    torch.testing.assert_close(gradient_loss(a, b, 4),
                               gradient_loss(a.roll(4, 3), b.roll(4, 3), 4))
    with pytest.raises(ShapeError, match=r"divisible by 2\^\(levels-1\) = 8"):
        gradient_loss(torch.zeros(1, 1, 4, 8), torch.zeros(1, 1, 4, 8), levels=4)


# ----------------------------------------------------------------------------- peak
def test_peak_mask_selects_union_of_top_pixels():
    # 10 x 20 = 200 pixels, fraction 2 % -> the 4 brightest of each image.
    pred = torch.ones(2, 3, 10, 20)
    target = torch.ones(2, 3, 10, 20)
    pred_hot = [(0, 0), (1, 5), (9, 19), (4, 4)]
    target_hot = [(0, 0), (2, 2), (3, 3), (5, 17)]  # (0, 0) shared with pred
    for k, (i, j) in enumerate(pred_hot):
        pred[0, :, i, j] = 100.0 + k
    for k, (i, j) in enumerate(target_hot):
        target[0, :, i, j] = 10.0 + k
    # Sample 1: luminance ranking must use Rec.709 weights: pure green beats pure red.
    target[1] = 0.0
    target[1, 0, 0, :4] = 1.0  # red, Y = 0.2126
    target[1, 1, 1, :4] = 0.5  # green, Y = 0.3576  <- these four are the top
    mask = peak_mask(pred, target, fraction=0.02)
    assert mask.shape == (2, 1, 10, 20)
    expected0 = {(0, 0), (1, 5), (9, 19), (4, 4), (2, 2), (3, 3), (5, 17)}
    got0 = {tuple(p) for p in mask[0, 0].nonzero().tolist()}
    assert got0 == expected0
    got1_target = {tuple(p) for p in top_fraction_mask(
        (target[1:] * torch.tensor([0.2126, 0.7152, 0.0722]).view(1, 3, 1, 1)).sum(1, True),
        0.02)[0, 0].nonzero().tolist()}
    assert got1_target == {(1, 0), (1, 1), (1, 2), (1, 3)}
    # k = ceil(0.005 * 200) = 1 pixel per image at the paper's fraction.
    assert top_fraction_mask(pred[:1, :1], 0.005).sum() == 1


def test_peak_loss_hand_value():
    pred = torch.ones(2, 3, 10, 20)
    target = torch.ones(2, 3, 10, 20)
    pred[0, :, 0, 0:4] = 100.0   # hallucinated emitter (4 px)
    target[0, :, 5, 0:4] = 10.0  # missed emitter (4 px)
    pred[1, :, 2, 0:4] = 7.0     # same emitter, wrong intensity
    target[1, :, 2, 0:4] = 3.5
    eps = 1e-6
    a = abs(math.log(100 + eps) - math.log(1 + eps))
    b = abs(math.log(1 + eps) - math.log(10 + eps))
    c = abs(math.log(7 + eps) - math.log(3.5 + eps))
    # Sample 0: |M| = 8, sample 1: |M| = 4 (masks coincide); pooled over the batch.
    expected = (4 * 3 * a + 4 * 3 * b + 4 * 3 * c) / (3 * 12)
    got = peak_loss(pred, target, fraction=0.02)
    assert got.item() == pytest.approx(expected, rel=1e-6)
    assert peak_loss(target, target, fraction=0.02).item() == 0.0


def test_peak_loss_has_gradients_only_on_the_mask():
    # pred differs from target everywhere, but only its own top pixel (7, 7) and the target's
    # top pixel (3, 3) are in the mask (k = ceil(0.005 * 200) = 1 per image).
    pred = (1.0 + torch.linspace(0, 0.5, 200).view(1, 1, 10, 20).expand(1, 3, 10, 20)).clone()
    pred[0, :, 7, 7] = 2.0
    pred.requires_grad_()
    target = torch.ones(1, 3, 10, 20)
    target[0, :, 3, 3] = 50.0
    peak_loss(pred, target, fraction=0.005).backward()
    nz = {tuple(p) for p in pred.grad[0, 0].nonzero().tolist()}
    assert nz == {(3, 3), (7, 7)}


# ----------------------------------------------------------------------------- KL
def test_kl_closed_form_hand_value():
    mean = torch.tensor([[1.0, 0.0], [0.0, 0.0]])
    std = torch.tensor([[2.0, 0.5], [1.0, 1.0]])
    logvar = torch.log(std**2)
    per_sample0 = 0.5 * ((1 + 4 - 1 - math.log(4)) + (0 + 0.25 - 1 - math.log(0.25)))
    expected = (per_sample0 + 0.0) / 2  # sample 1 equals the prior: KL 0
    assert kl_divergence(mean, logvar).item() == pytest.approx(expected, rel=1e-6)


def test_kl_matches_monte_carlo_and_torch_distributions():
    g = torch.Generator().manual_seed(0)
    mean = torch.randn(3, 5, dtype=torch.float64, generator=g)
    logvar = torch.randn(3, 5, dtype=torch.float64, generator=g) * 0.5
    q = torch.distributions.Normal(mean, torch.exp(0.5 * logvar))
    p = torch.distributions.Normal(torch.zeros_like(mean), torch.ones_like(mean))
    analytic = torch.distributions.kl_divergence(q, p).sum(1).mean()
    torch.testing.assert_close(kl_divergence(mean, logvar), analytic)
    torch.manual_seed(0)
    z = q.sample((200_000,))
    mc = (q.log_prob(z) - p.log_prob(z)).sum(-1).mean()
    assert kl_divergence(mean, logvar).item() == pytest.approx(mc.item(), rel=0.02)


def test_kl_weight_schedule():
    assert kl_weight(0) == 0.0
    assert kl_weight(250) == pytest.approx(2.5e-4)
    assert kl_weight(1000) == pytest.approx(1e-3)
    assert kl_weight(10_000) == pytest.approx(1e-3)
    assert kl_weight(50, beta=0.5, warmup=100) == pytest.approx(0.25)
    assert kl_weight(0, beta=0.5, warmup=0) == 0.5
    assert kl_weight(-5) == 0.0


# ----------------------------------------------------------------------------- total
def test_vae_loss_combines_terms_with_paper_weights():
    norm = Normalization(mean=(0.9, 0.8, 0.5, 0.0), std=(0.6, 0.6, 0.55, 0.46))
    g = torch.Generator().manual_seed(0)
    radiance = torch.rand(2, 3, 8, 16, generator=g) * 3
    radiance[:, :, 2, 3] = 200.0
    depth = torch.rand(2, 1, 8, 16, generator=g) + 1.0
    x = norm.normalize(radiance, depth)
    x_hat = (x + 0.3 * torch.randn(x.shape, generator=g)).requires_grad_()
    mean, logvar = torch.randn(2, 6, generator=g), torch.randn(2, 6, generator=g) * 0.1
    terms = vae_loss(x_hat, x, mean, logvar, step=500, normalization=norm,
                     target_radiance=radiance)
    assert set(terms) == {"l1_radiance", "l1_depth", "grad_radiance", "grad_depth", "peak", "kl",
                          "kl_weight", "total"}
    pred_rad, _ = norm.denormalize(x_hat)
    torch.testing.assert_close(terms["l1_depth"], (x_hat[:, 3] - x[:, 3]).abs().mean())
    torch.testing.assert_close(terms["grad_radiance"], gradient_loss(x_hat[:, :3], x[:, :3], 4))
    torch.testing.assert_close(terms["peak"], peak_loss(pred_rad, radiance))
    assert terms["kl_weight"].item() == pytest.approx(5e-4)
    expected = (terms["l1_radiance"] + terms["l1_depth"] + 2 * terms["grad_radiance"]
                + terms["grad_depth"] + 0.1 * terms["peak"] + 5e-4 * terms["kl"])
    torch.testing.assert_close(terms["total"], expected)
    terms["total"].backward()
    assert torch.isfinite(x_hat.grad).all() and x_hat.grad.abs().sum() > 0
    # A perfect reconstruction leaves only the KL term.
    perfect = vae_loss(x, x, mean, logvar, step=2000, normalization=norm, config=LossConfig())
    for k in ("l1_radiance", "l1_depth", "grad_radiance", "grad_depth"):
        assert perfect[k].item() == 0.0
    assert perfect["peak"].item() < 1e-5
    torch.testing.assert_close(perfect["total"], 1e-3 * perfect["kl"] + 0.1 * perfect["peak"])


def test_peak_loss_per_sample_is_each_panoramas_own_peak_loss():
    from roomlight.prior.losses import peak_loss_per_sample

    g = torch.Generator().manual_seed(3)
    pred = torch.rand(3, 3, 8, 16, generator=g) * torch.tensor([1.0, 5.0, 50.0]).view(3, 1, 1, 1)
    target = torch.rand(3, 3, 8, 16, generator=g) * 20.0
    per = peak_loss_per_sample(pred, target, fraction=0.05)
    assert per.shape == (3,)
    for i in range(3):  # alone in its batch, each panorama's batch loss is its own value
        torch.testing.assert_close(per[i], peak_loss(pred[i:i + 1], target[i:i + 1], fraction=0.05))
    # The batch loss weighs panoramas by their mask sizes; with equal masks it is the plain mean.
    k = math.ceil(0.05 * 8 * 16)
    same = torch.zeros(2, 3, 8, 16)
    same.view(2, 3, -1)[:, :, :k] = 10.0
    other = same * torch.tensor([2.0, 3.0]).view(2, 1, 1, 1)
    torch.testing.assert_close(peak_loss(other, same), peak_loss_per_sample(other, same).mean())
    torch.testing.assert_close(peak_loss_per_sample(other, same), torch.log(torch.tensor([2.0, 3.0])), atol=1e-6,
                               rtol=1e-5)
