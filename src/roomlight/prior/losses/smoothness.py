"""The smoothness prior of the direct-optimisation baselines (NeRFactor-style, paper supp.).

Sum of squared one-pixel finite differences of a field on the equirectangular grid, with
"wrap-around on both axes" as in the paper: on the sphere every pixel has four neighbours.
Longitude wraps at the seam; across a pole the neighbour of row 0 at column j is row 0 at
column j + W/2 (and likewise for the last row), the same rule as the spherical padding of
:mod:`roomlight.core.geometry.padding` (docs/conventions.md, "Spherical padding"). Every
neighbouring pair is counted once.
"""

from __future__ import annotations

import torch

from roomlight.errors import ShapeError

__all__ = ["smoothness"]


def smoothness(field: torch.Tensor) -> torch.Tensor:
    """sum over neighbouring pixel pairs (a, b) on the sphere of (f_a - f_b)^2.

    Args:
        field: (H, W) or (H, W, C) on the equirectangular grid, W even.
    Returns:
        scalar: H * W longitude pairs, (H - 1) * W latitude pairs and W/2 pairs across each pole.
    """
    w = field.shape[1]
    if w % 2:
        raise ShapeError(f"smoothness: the width must be even to wrap across the poles, got {tuple(field.shape)}")
    half = w // 2
    du = torch.roll(field, shifts=-1, dims=1) - field      # longitude, wraps at the seam
    dv = field[1:] - field[:-1]                            # latitude, inside the grid
    north = field[0, half:] - field[0, :half]              # across the north pole: j <-> j + W/2
    south = field[-1, half:] - field[-1, :half]            # across the south pole
    return du.square().sum() + dv.square().sum() + north.square().sum() + south.square().sum()
