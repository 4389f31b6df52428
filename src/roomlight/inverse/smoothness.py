"""The smoothness prior of the direct-optimisation baselines (NeRFactor-style, paper supp.).

Sum of squared one-pixel finite differences of a field on the equirectangular grid. Differences
wrap around in longitude (the seam is not an edge) but not across the poles: the top and bottom
rows have no vertical neighbour beyond the pole (DESIGN.md §4).
"""

from __future__ import annotations

import torch

__all__ = ["smoothness"]


def smoothness(field: torch.Tensor) -> torch.Tensor:
    """sum_i (Delta_u f)_i^2 + (Delta_v f)_i^2 for a field (H, W) or (H, W, C) -> scalar."""
    du = torch.roll(field, shifts=-1, dims=1) - field      # longitude, wraps at the seam
    dv = field[1:] - field[:-1]                            # latitude, no wrap across the poles
    return du.square().sum() + dv.square().sum()
