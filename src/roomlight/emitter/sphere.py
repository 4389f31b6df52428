"""The sphere-proxy emitter: the panorama's radiance on a sphere of fixed radius.

It is the 2.5D area light with a constant depth map, so it shares the mesh, its texture
mapping and its orientation; only the geometry is frozen (the "Smoothness: sphere proxy"
baseline of the paper).
"""

from __future__ import annotations

import torch

from roomlight.emitter.area_light import AreaLightMesh, build_area_light
from roomlight.errors import ShapeError

__all__ = ["sphere_depth", "build_sphere_emitter", "enclosing_radius"]


def sphere_depth(height: int, width: int, radius: float, dtype=torch.float32, device=None) -> torch.Tensor:
    """(H, W) constant depth map of a sphere of ``radius`` scene units around the capture point."""
    if not radius > 0:
        raise ShapeError(f"sphere emitter: radius must be > 0, got {radius}")
    return torch.full((height, width), float(radius), dtype=dtype, device=device)


def build_sphere_emitter(radiance: torch.Tensor, radius: float) -> AreaLightMesh:
    """(H, W, 3) radiance on an origin-centred sphere of ``radius`` (inward-facing mesh)."""
    h, w = radiance.shape[:2]
    return build_area_light(radiance, sphere_depth(h, w, radius, radiance.dtype, radiance.device))


def enclosing_radius(points: torch.Tensor, margin: float = 0.2) -> float:
    """Radius of the smallest origin-centred sphere enclosing ``points`` (N, 3), enlarged by
    ``margin`` (0.2 = +20 %, the paper's sphere-proxy rule)."""
    return float(points.norm(dim=-1).max()) * (1.0 + margin)
