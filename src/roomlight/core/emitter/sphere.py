"""The sphere-proxy emitter: the panorama's radiance on a sphere of fixed radius.

It is the 2.5D area light with a constant depth map, so it shares the mesh, its texture
mapping and its orientation; only the geometry is frozen (the "Smoothness: sphere proxy"
baseline of the paper). The radius the fits use encloses every object of the scene by a
margin: :func:`roomlight.fitting.inverse.methods.enclosing_sphere_radius`.
"""

from __future__ import annotations

import torch

from roomlight.errors import ShapeError

__all__ = ["sphere_depth"]


def sphere_depth(height: int, width: int, radius: float, dtype=torch.float32, device=None) -> torch.Tensor:
    """(H, W) constant depth map of a sphere of ``radius`` scene units around the capture point."""
    if not radius > 0:
        raise ShapeError(f"sphere emitter: radius must be > 0, got {radius}")
    return torch.full((height, width), float(radius), dtype=dtype, device=device)
