"""The smoothness prior of the direct-optimisation baselines; it lives with the other loss terms in
:mod:`roomlight.prior.losses.smoothness` (the pixel-level reference fits use it too)."""

from __future__ import annotations

from roomlight.prior.losses.smoothness import smoothness

__all__ = ["smoothness"]
