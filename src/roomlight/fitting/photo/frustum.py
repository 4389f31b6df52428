"""The frustum constraint: inside the camera's view, the light must look like the photograph.

The unmasked part of the photograph shows the room itself, i.e. the light source: a pixel that
sees a room surface at the point q (room frame, after the scene transform) says that the
emitter, in q's direction from its centre, has the pixel's radiance and reaches out to |q|.

- radiance: the same censored image objective as the objects' pixels (:func:`image_loss`), between
  the emitter's radiance L(q / |q|) (bilinear on the panorama) and the pixel's radiance;
- depth (2.5D emitters only): mean over the pixels of (log D(q / |q|) - log |q|)^2.

An env map has no position: what the camera sees in a pixel is the env map in the pixel's
viewing direction, so its radiance term samples the rays' directions and it has no depth term.
"""

from __future__ import annotations

import torch

from roomlight.core.geometry.equirect import sample_equirect
from roomlight.fitting.inverse.objective import image_loss

__all__ = ["FrustumTarget", "frustum_terms"]


class FrustumTarget:
    """Frustum observations in the room frame, as tensors.

    Args:
        points: (N, 3) room-frame points the pixels see (metres of the room).
        rays: (N, 3) room-frame unit viewing directions.
        radiance: (N, 3) the pixels' linear radiance.
    """

    def __init__(self, points, rays, radiance):
        self.points = torch.as_tensor(points, dtype=torch.float32)
        self.rays = torch.as_tensor(rays, dtype=torch.float32)
        self.radiance = torch.as_tensor(radiance, dtype=torch.float32)
        self.distance = self.points.norm(dim=-1)

    def __len__(self) -> int:
        return len(self.points)


def frustum_terms(radiance: torch.Tensor, depth: torch.Tensor | None, target: FrustumTarget, tau: float = 0.99,
                  c_max: float = 10.0, lambda_log: float = 0.01, log_eps: float = 1e-3) -> dict[str, torch.Tensor]:
    """The frustum terms of an emitter.

    Args:
        radiance: (H, W, 3) the emitter's linear radiance (exposure applied).
        depth: (H, W) its radial depth in metres, or None for an env map.
        target: the observations.
    Returns:
        ``frustum``: the censored image objective over the observed pixels; with ``depth`` also
        ``frustum_depth``: mean (log D - log |q|)^2.
    """
    dirs = target.points if depth is not None else target.rays
    dirs = dirs.to(radiance.device)
    emitted = sample_equirect(radiance.permute(2, 0, 1)[None], dirs)[0].T  # (N, 3)
    obs = target.radiance.to(radiance.device)
    ones = torch.ones(1, len(target), dtype=torch.bool, device=radiance.device)
    out = {"frustum": image_loss(emitted[None], obs[None], ones, tau, c_max, lambda_log, log_eps)["img"]}
    if depth is not None:
        d = sample_equirect(depth[None, None], dirs)[0, 0]
        out["frustum_depth"] = (torch.log(d.clamp_min(1e-6)) - torch.log(target.distance.to(d.device))).square().mean()
    return out
