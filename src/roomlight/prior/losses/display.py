"""The tone-mapped error of a panorama: what its PSNR LDR scores, as a loss.

The prior's evaluation scores a panorama in display values (:func:`roomlight.core.color.to_display_at_key`):
both images exposed so that the *target's* log-average luminance is middle grey, clipped to [0, 1],
gamma 2.2; PSNR LDR is ``-10 log10`` of their mean squared difference. The same squared difference,
as a loss, asks for what that score sees: the level and layout of the mid-tones and of the lamps up to
where they clip, not their exact peak (the peak term's business), and a dark corner's error by how much
it shows (the z-scored L1 term weighs it as much as a lamp's).

    L_display = mean_{b, c, h, w} ( D(k_b x^) - D(k_b x) )^2,   D(y) = clamp(y, 0, 1)^(1 / 2.2),
    k_b = 0.18 / logavg(x_b)

The clip has no gradient above 1. A prediction over-exposed where the target is not would get none and
stay there, so above the clip the gradient is carried on with the display curve's slope at 1 (1 / 2.2);
where the target clips too the two display values are equal and the gradient is 0 all the same. The
curve's slope is taken 1e-6 above each value (finite at black, where the true one is infinite). The
loss's *value* is the display error exactly; its gradient is steepest near black (about 850 k at 0
against about 1.2 k at middle grey), so a guess far too dark in a dark corner is still pulled up.
Negative predictions get no gradient (a decoded room is never negative).
"""

from __future__ import annotations

import torch

from roomlight.core.color import DISPLAY_GAMMA, MIDDLE_GREY, log_average_torch
from roomlight.errors import ShapeError
from roomlight.prior.losses.l1 import check_same_shape

__all__ = ["display_loss"]

#: Floor under the exposed values before the gamma, so its slope stays finite at black.
_BLACK = 1e-6


def display_loss(pred: torch.Tensor, target: torch.Tensor) -> torch.Tensor:
    """Mean squared difference of ``pred`` and ``target`` in display values at the target's key.

    Args:
        pred, target: (B, 3, H, W) linear radiance (calibrated units; only their ratio to the target's
            log-average matters).
    Returns:
        () the mean over batch, channels and pixels; ``10 log10(1 / value)`` of one image is its PSNR LDR.
    """
    check_same_shape(pred, target, "display_loss")
    if pred.dim() != 4 or pred.shape[1] != 3:
        raise ShapeError(f"display_loss: expected (B, 3, H, W) radiance, got {tuple(pred.shape)}")
    k = (MIDDLE_GREY / log_average_torch(target.detach())).view(-1, 1, 1, 1).to(pred.dtype)
    p, t = pred * k, target * k
    exponent = 1.0 / DISPLAY_GAMMA
    d_t = t.clamp(0.0, 1.0) ** exponent
    # the value exactly as the metric maps it; the gradient from the curve floored at _BLACK (finite at black)
    d_floor = (p.clamp(0.0, 1.0) + _BLACK) ** exponent
    d_p = (p.clamp(0.0, 1.0) ** exponent).detach() + (d_floor - d_floor.detach())
    # above the clip the value stays 1 and the gradient is the curve's slope at 1 (0 anyway where t clips)
    over = p > 1.0
    d_p = d_p + torch.where(over, (p - p.detach()) * exponent, torch.zeros_like(p))
    return (d_p - d_t).square().mean()
