"""Training losses of the prior (paper §3.3, eq. 3-6); pure functions on (B, C, H, W) tensors.

- :func:`l1_loss`         pixel-wise L1 (z-scored domain)
- :func:`gradient_loss`   multi-scale normalised Scharr gradients with spherical padding
- :func:`peak_loss`       log-L1 over the brightest 0.5 % of pixels (linear radiance)
- :func:`kl_divergence`   closed-form KL to N(0, I); :func:`kl_weight` its annealing
- :func:`vae_loss`        the weighted sum, returning every term
- :func:`smoothness`      squared neighbour differences on the sphere (the direct baselines' prior)
"""

from __future__ import annotations

from roomlight.prior.losses.gradient import SCHARR_U, SCHARR_V, gradient_loss, scharr_gradients
from roomlight.prior.losses.kl import kl_divergence, kl_weight
from roomlight.prior.losses.l1 import l1_loss
from roomlight.prior.losses.peak import luminance, peak_loss, peak_loss_per_sample, peak_mask, top_fraction_mask
from roomlight.prior.losses.smoothness import smoothness
from roomlight.prior.losses.total import LossConfig, vae_loss

__all__ = [
    "l1_loss", "gradient_loss", "scharr_gradients", "SCHARR_U", "SCHARR_V", "peak_loss",
    "peak_loss_per_sample", "peak_mask", "top_fraction_mask", "luminance", "kl_divergence", "kl_weight", "LossConfig",
    "vae_loss", "smoothness",
]
