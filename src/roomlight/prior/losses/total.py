"""The full training objective of the prior (paper eq. 3).

L = L1^L + L1^D + 2 L_grad^L + L_grad^D + 0.1 L_peak + beta_t L_KL
"""

from __future__ import annotations

from dataclasses import dataclass

import torch

from roomlight.core.config import StrictConfig
from roomlight.errors import ShapeError
from roomlight.prior.losses.gradient import gradient_loss
from roomlight.prior.losses.kl import kl_divergence, kl_weight
from roomlight.prior.losses.l1 import l1_loss
from roomlight.prior.losses.peak import peak_loss

__all__ = ["LossConfig", "vae_loss"]


@dataclass(frozen=True)
class LossConfig(StrictConfig):
    """Weights and settings of the training objective (defaults: the paper's)."""

    #: Weight of the L1 loss on z-scored log1p radiance.
    l1_radiance: float = 1.0
    #: Weight of the L1 loss on z-scored log depth.
    l1_depth: float = 1.0
    #: Weight of the Scharr gradient loss on z-scored radiance.
    grad_radiance: float = 2.0
    #: Weight of the Scharr gradient loss on z-scored depth.
    grad_depth: float = 1.0
    #: Weight of the peak loss on linear radiance.
    peak: float = 0.1
    #: Final KL weight beta.
    kl_beta: float = 1e-3
    #: Optimiser steps over which the KL weight ramps linearly from 0 to beta.
    kl_warmup_steps: int = 1000
    #: Octaves S of the gradient-loss pyramid.
    grad_levels: int = 4
    #: Share of the brightest pixels per image forming the peak mask.
    peak_fraction: float = 0.005
    #: Offset inside the peak loss's log.
    peak_eps: float = 1e-6


def vae_loss(x_hat: torch.Tensor, x: torch.Tensor, mean: torch.Tensor, logvar: torch.Tensor,
             step: int, normalization, target_radiance: torch.Tensor | None = None,
             config: LossConfig = LossConfig()) -> dict[str, torch.Tensor]:
    """All terms of the objective and their weighted sum.

    Args:
        x_hat: (B, 4, H, W) decoder output in the z-scored domain.
        x: (B, 4, H, W) z-scored input (channels log1p R, G, B, log depth).
        mean, logvar: (B, D) posterior parameters.
        step: optimiser step, for the KL annealing.
        normalization: a :class:`~roomlight.prior.model.normalization.Normalization` (anything with
            ``denormalize(x) -> (radiance, depth)``), to reach linear radiance for the peak loss.
        target_radiance: (B, 3, H, W) linear ground truth; defaults to denormalising ``x``
            (identical up to rounding and the 1e6 clamp).
        config: weights and settings.
    Returns:
        dict with the unweighted terms ``l1_radiance``, ``l1_depth``, ``grad_radiance``,
        ``grad_depth``, ``peak``, ``kl``, the scalar ``kl_weight`` used, and the weighted
        ``total`` (the only one to backpropagate).
    """
    if x_hat.shape != x.shape or x.dim() != 4 or x.shape[1] != 4:
        raise ShapeError(
            f"vae_loss: expected x_hat and x of the same shape (B, 4, H, W), got "
            f"{tuple(x_hat.shape)} and {tuple(x.shape)}"
        )
    pred_radiance, _ = normalization.denormalize(x_hat)
    if target_radiance is None:
        target_radiance, _ = normalization.denormalize(x)
    beta_t = kl_weight(step, config.kl_beta, config.kl_warmup_steps)
    terms = {
        "l1_radiance": l1_loss(x_hat[:, :3], x[:, :3]),
        "l1_depth": l1_loss(x_hat[:, 3:], x[:, 3:]),
        "grad_radiance": gradient_loss(x_hat[:, :3], x[:, :3], config.grad_levels),
        "grad_depth": gradient_loss(x_hat[:, 3:], x[:, 3:], config.grad_levels),
        "peak": peak_loss(pred_radiance, target_radiance, config.peak_fraction, config.peak_eps),
        "kl": kl_divergence(mean, logvar),
    }
    weights = {
        "l1_radiance": config.l1_radiance, "l1_depth": config.l1_depth,
        "grad_radiance": config.grad_radiance, "grad_depth": config.grad_depth,
        "peak": config.peak, "kl": beta_t,
    }
    terms["total"] = sum(weights[k] * terms[k] for k in weights)
    terms["kl_weight"] = x_hat.new_tensor(beta_t)
    return terms
