"""Keeping the 2.5D area light out of the objects (paper eq. 10; docs/inverse-rendering.md).

For an object point q the clearance is g(q) = D(dir q) - |q|: the emitter's depth in q's
direction (bilinear on the depth map, seam- and pole-continuous) minus q's distance from the
capture point. It is positive while the emitter encloses q. The penalty is the hinge
max(m - g, 0) averaged over points, with the margin m in metres (scene units).

Because g is a continuous function of the depth map and of q, the penalty is continuous: zero
while every point has at least m of clearance, then growing linearly as the emitter closes in
and crosses the object (there is no jump when the surface passes through q).
"""

from __future__ import annotations

import torch

from roomlight.core.geometry.equirect import sample_equirect

__all__ = ["clearance", "repulsion_penalty"]


def clearance(depth: torch.Tensor, points: torch.Tensor) -> torch.Tensor:
    """g(q) for points (M, 3) against a depth map (H, W) -> (M,) metres (positive inside)."""
    d = sample_equirect(depth[None, None], points.to(depth.dtype))[0, 0]
    return d - points.to(depth.dtype).norm(dim=-1)


def repulsion_penalty(depth: torch.Tensor, points: torch.Tensor, margin: float) -> torch.Tensor:
    """mean_q max(m - g(q), 0), a scalar in metres."""
    return torch.relu(margin - clearance(depth, points)).mean()
