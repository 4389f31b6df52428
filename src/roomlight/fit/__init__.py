"""Fitting the prior to observations. So far: latent fitting to a panorama (``roomlight fit-pano``).

- :class:`FitConfig`, :func:`fit_latent`, :class:`FitResult`
"""

from __future__ import annotations

from roomlight.fit.latent import TARGETS, FitConfig, FitResult, fit_latent

__all__ = ["FitConfig", "FitResult", "fit_latent", "TARGETS"]
