"""The image objective of illumination fitting (paper eq. 8-9): censoring and the masked loss.

The target is a low-dynamic-range recording: a saturated pixel only says the radiance exceeded
the sensor's limit. The render is censored the same way before the comparison, so a saturated
pixel constrains the light only from below, and an unsaturated one is kept up to a loose
ceiling ``c_max`` that stops one over-bright Monte-Carlo sample from dominating the gradient.
"""

from __future__ import annotations

import torch

__all__ = ["censor", "image_loss"]


def censor(render: torch.Tensor, target: torch.Tensor, tau: float = 0.99, c_max: float = 10.0) -> torch.Tensor:
    """Censored render R~ (same shape as ``render``, (..., 3)).

    R~ = min(R, 1) where max_c I >= tau (saturated target pixel), else min(R, c_max).
    """
    saturated = target.amax(dim=-1, keepdim=True) >= tau
    ceiling = torch.where(saturated, torch.ones_like(render), torch.full_like(render, c_max))
    return torch.minimum(render, ceiling)


def image_loss(render: torch.Tensor, target: torch.Tensor, mask: torch.Tensor, tau: float = 0.99,
               c_max: float = 10.0, lambda_log: float = 0.1, log_eps: float = 1e-3) -> dict[str, torch.Tensor]:
    """L_img over the masked pixels.

    Args:
        render: (H, W, 3) linear render R.
        target: (H, W, 3) linear target I (an LDR recording, linearised, in [0, 1]).
        mask: (H, W) bool, the object pixels Omega (or a subset of them).
    Returns:
        dict with ``l2`` = mean_i ||R~_i - I_i||^2, ``log`` = mean_i ||log(R~_i + eps) - log(I_i + eps)||^2
        and ``img`` = l2 + lambda_log * log (squared norms summed over RGB, averaged over pixels).
    """
    r = censor(render, target, tau, c_max)[mask]
    t = target[mask]
    n = max(int(mask.sum()), 1)
    l2 = (r - t).square().sum() / n
    lg = (torch.log(r.clamp(min=0) + log_eps) - torch.log(t + log_eps)).square().sum() / n
    return {"l2": l2, "log": lg, "img": l2 + lambda_log * lg}
