"""Peak (light-source) loss on linear radiance (paper eq. 5).

L_peak = 1/(3|M|) * sum_{i in M} sum_{c in RGB} |log(pred_ic + eps) - log(target_ic + eps)|

M is, per sample, the union of the top ``fraction`` (0.5 %) pixels by Rec.709 luminance of the
prediction and of the target, so both missed and hallucinated emitters are penalised. |M| counts
the masked pixels of the whole batch (the formula's sum runs over one set M spanning all
samples), so samples whose masks overlap less weigh slightly more.
"""

from __future__ import annotations

import math

import torch

from roomlight.core.color import luminance_torch
from roomlight.errors import ShapeError
from roomlight.prior.losses.l1 import check_same_shape

__all__ = ["luminance", "top_fraction_mask", "peak_mask", "peak_loss", "peak_loss_per_sample"]

def luminance(rgb: torch.Tensor) -> torch.Tensor:
    """Rec.709 luminance of linear RGB: (B, 3, H, W) -> (B, 1, H, W)."""
    if rgb.dim() != 4 or rgb.shape[1] != 3:
        raise ShapeError(f"luminance: expected (B, 3, H, W) linear RGB, got {tuple(rgb.shape)}")
    return luminance_torch(rgb, keepdim=True)


def top_fraction_mask(values: torch.Tensor, fraction: float) -> torch.Tensor:
    """Per-sample mask of the k largest values, k = max(1, ceil(fraction * H * W)).

    Args:
        values: (B, 1, H, W).
    Returns:
        (B, 1, H, W) bool with exactly k True entries per sample (ties broken by ``topk``).
    """
    if not 0.0 < fraction <= 1.0:
        raise ValueError(f"top_fraction_mask: fraction must be in (0, 1], got {fraction}")
    b = values.shape[0]
    flat = values.detach().reshape(b, -1)
    k = max(1, math.ceil(fraction * flat.shape[1]))
    idx = flat.topk(k, dim=1).indices
    mask = torch.zeros_like(flat, dtype=torch.bool).scatter_(1, idx, True)
    return mask.view_as(values)


def peak_mask(pred: torch.Tensor, target: torch.Tensor, fraction: float = 0.005) -> torch.Tensor:
    """Union of the brightest ``fraction`` of pixels of ``pred`` and of ``target``.

    Args:
        pred, target: (B, 3, H, W) linear radiance.
    Returns:
        (B, 1, H, W) bool, not differentiable (selection only).
    """
    check_same_shape(pred, target, "peak_mask")
    return top_fraction_mask(luminance(pred), fraction) | top_fraction_mask(luminance(target), fraction)


def _masked_log_error(pred: torch.Tensor, target: torch.Tensor, fraction: float,
                      eps: float) -> tuple[torch.Tensor, torch.Tensor]:
    """(B, 3, H, W) |log(pred + eps) - log(target + eps)| zeroed outside the peak mask, and the mask."""
    mask = peak_mask(pred, target, fraction)  # (B, 1, H, W)
    err = (torch.log(pred.clamp_min(0.0) + eps) - torch.log(target.clamp_min(0.0) + eps)).abs()
    return err * mask, mask  # the mask broadcasts over the 3 channels


def peak_loss(pred: torch.Tensor, target: torch.Tensor, fraction: float = 0.005,
              eps: float = 1e-6) -> torch.Tensor:
    """Log-L1 over the peak mask (paper eq. 5).

    Args:
        pred: (B, 3, H, W) decoded linear radiance (negative values are clamped to 0).
        target: (B, 3, H, W) ground-truth linear radiance (exposure calibrated).
        fraction: share of pixels per image and per source taken as peaks (0.005).
        eps: offset inside the log, so black pixels stay finite.
    Returns:
        scalar tensor.
    """
    err, mask = _masked_log_error(pred, target, fraction, eps)
    return err.sum() / (3.0 * mask.sum())


def peak_loss_per_sample(pred: torch.Tensor, target: torch.Tensor, fraction: float = 0.005,
                         eps: float = 1e-6) -> torch.Tensor:
    """The peak loss of each panorama on its own: (B,) means over its own mask.

    :func:`peak_loss` divides by the masked pixels of the whole batch; where each panorama is
    optimised separately (a latent fit), its value must not depend on the other panoramas.
    Arguments as :func:`peak_loss`.
    """
    err, mask = _masked_log_error(pred, target, fraction, eps)
    return err.flatten(1).sum(1) / (3.0 * mask.flatten(1).sum(1))
