"""Pixel-level reference fits: a free panorama under the smoothness prior (the paper's Table 1 rows
"Smooth. HDR" and "Smooth. HDRD").

The same objective and optimiser as the latent fit (:func:`roomlight.prior.latent_fit.latent.fit_latent`): Adam
from the mean panorama (0 in the normalised space), the learning rate decayed exponentially, the
weighted squared error of the normalised channels (+ the peak term when the latent fit has one);
the latent is replaced by every normalised pixel, and the NeRFactor-style smoothness of the direct
baselines (:func:`roomlight.prior.losses.smoothness.smoothness`, squared differences of neighbouring
pixels on the sphere) is added to each panorama's objective, per channel and per pixel:

    objective = weighted MSE + smoothness_weight * sum over fitted channels of smoothness(x_c) / (H W)

There is no bottleneck, so these rows measure the regularisation the smoothness prior imposes at
that weight, not the fidelity of a compact representation.
"""

from __future__ import annotations

import torch

from roomlight.prior.latent_fit.latent import LatentFitConfig, LatentFitResult, fit_problem, optimise
from roomlight.prior.losses.smoothness import smoothness

__all__ = ["fit_pixels", "DEFAULT_SMOOTHNESS"]

#: Weight of the smoothness term per fitted channel and pixel, against the mean squared error of the
#: normalised channels (chosen, not the paper's: the paper does not give the weight of these rows).
DEFAULT_SMOOTHNESS = 0.05


def fit_pixels(radiance: torch.Tensor | None, depth: torch.Tensor | None, config: LatentFitConfig = LatentFitConfig(),
               *, normalization, smoothness_weight: float = DEFAULT_SMOOTHNESS, callback=None) -> LatentFitResult:
    """Fit a free normalised panorama per input to radiance (B, 3, H, W) and/or depth (B, 1, H, W).

    ``config.target`` selects the channels (``radiance``: HDR, ``both``: HDRD); the encoder start and
    the latent do not apply. Returns a :class:`LatentFitResult` whose ``z`` is the fitted normalised
    panorama (B, C, H, W); ``depth`` is None when depth was not fitted.
    """
    ref = radiance if radiance is not None else depth
    h, w = ref.shape[-2:]
    problem = fit_problem(normalization, (h, w), radiance, depth, config)
    b, c = problem.x.shape[:2]

    def decode(x):  # the fitted channels in place, the others at the placeholder target's values
        full = normalization.normalize(problem.radiance, problem.depth).clone()
        full[:, problem.channels] = x
        return full

    def regularizer(x):  # (B,)
        return smoothness_weight * torch.stack([
            sum(smoothness(x[i, k]) for k in range(c)) / (h * w) for i in range(b)])

    x0 = torch.zeros(b, c, h, w, device=ref.device)
    best, loss, history = optimise(x0, decode, problem, config, callback, regularizer)
    with torch.no_grad():
        rad, dep = normalization.denormalize(decode(best))
    return LatentFitResult(best, loss, rad, dep if 3 in problem.channels else None, history)
