"""KL regulariser of the VAE posterior and its annealing schedule (paper eq. 6)."""

from __future__ import annotations

import torch

from roomlight.prior.losses.l1 import check_same_shape

__all__ = ["kl_divergence", "kl_weight"]


def kl_divergence(mean: torch.Tensor, logvar: torch.Tensor) -> torch.Tensor:
    """Closed-form KL(N(mean, diag exp(logvar)) || N(0, I)).

    0.5 * sum_j (mean_j^2 + exp(logvar_j) - 1 - logvar_j), summed over the latent dimensions
    and averaged over the batch.

    Args:
        mean, logvar: (B, D) posterior parameters.
    Returns:
        scalar tensor (nats per sample).
    """
    check_same_shape(mean, logvar, "kl_divergence")
    per_sample = 0.5 * (mean.pow(2) + logvar.exp() - 1.0 - logvar).flatten(1).sum(dim=1)
    return per_sample.mean()


def kl_weight(step: int, beta: float = 1e-3, warmup: int = 1000) -> float:
    """Linearly annealed KL weight beta_t = beta * min(t / T_w, 1).

    ``step`` counts optimiser steps from 0 (weight 0 at the first step); ``warmup <= 0``
    disables the annealing.
    """
    if warmup <= 0:
        return float(beta)
    return float(beta) * min(max(step, 0) / warmup, 1.0)
