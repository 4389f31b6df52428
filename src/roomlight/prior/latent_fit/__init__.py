"""Latent fitting: the prior's latent that best reproduces a panorama (``roomlight fit-pano``).

Not to be confused with :mod:`roomlight.fitting.inverse`, which recovers a scene's light from an image
(``roomlight fit``).

- :class:`LatentFitConfig`, :func:`fit_latent`, :class:`LatentFitResult`
"""

from __future__ import annotations

from roomlight.prior.latent_fit.latent import TARGETS, LatentFitConfig, LatentFitResult, fit_latent

__all__ = ["LatentFitConfig", "LatentFitResult", "fit_latent", "TARGETS"]
