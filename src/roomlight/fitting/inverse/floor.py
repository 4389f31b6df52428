"""A hard guarantee that given points stay inside a 2.5D area light: a floor under its depth map.

The repulsion term (:mod:`roomlight.fitting.inverse.repulsion`) is a *mean* hinge over sampled points: a
few points left outside cost little, so part of the space a camera sees can end up behind the
emitter (an object there sees only the mesh's back faces and renders black). The floor removes
that possibility instead of discouraging it: every emitter pixel's depth is raised to at least

    F(cell) = max over points q whose direction lies in the cell or one of its 8 neighbours of
              |q| (1 + relative) + margin(q)

so D' = max(D, F). The mesh's vertices sit at pixel centres and the triangle a ray in q's
direction hits has its vertices among the 3 x 3 cells around q's cell, so every such vertex is
at least |q| (1 + relative) away; a flat triangle spanning a few degrees comes no closer to the
centre than cos(its angular size) times that, which ``relative`` (2 %) covers at the prior's
resolutions. Where D is already beyond the floor nothing changes (and the gradient is D's);
where it is not, the emitter is pushed out (a projection, with no gradient through the floor).
"""

from __future__ import annotations

import torch
import torch.nn.functional as F

from roomlight.core.geometry.equirect import direction_to_uv
from roomlight.core.geometry.padding import spherical_pad

__all__ = ["depth_floor", "apply_floor", "outside_share", "FLOOR_RELATIVE"]

#: Relative clearance added to every point's distance (covers the flat triangles between vertices).
FLOOR_RELATIVE = 0.02


def depth_floor(points: torch.Tensor, resolution: tuple[int, int], margin=0.0,
                relative: float = FLOOR_RELATIVE, neighbours: bool = True) -> torch.Tensor:
    """(H, W) float32 floor F (module docstring); 0 where no point constrains the cell.

    Args:
        points: (M, 3) points in the emitter's frame (its centre at the origin), metres.
        resolution: (H, W) of the emitter's depth map.
        margin: metres added to every point's distance: a number, or (M,) per point.
        relative: the relative clearance.
        neighbours: spread each point's need over the 3 x 3 cells around its own (the guarantee of the
            module docstring); False: its own cell only, so that the vertex at the cell's centre is beyond the
            point but a triangle's edge towards a nearer neighbour may pass in front of it.
    """
    h, w = (int(v) for v in resolution)
    q = torch.as_tensor(points, dtype=torch.float64).reshape(-1, 3)
    r = q.norm(dim=-1)
    keep = torch.isfinite(r) & (r > 0)
    need = r * (1.0 + relative) + torch.as_tensor(margin, dtype=torch.float64).expand_as(r)
    q, need = q[keep], need[keep]
    u, v = direction_to_uv(q)
    cell = (v * h).floor().long().clamp(0, h - 1) * w + (u * w).floor().long().clamp(0, w - 1)
    floor = torch.zeros(h * w, dtype=torch.float64)
    floor.scatter_reduce_(0, cell, need, reduce="amax", include_self=True)
    if not neighbours:
        return floor.reshape(h, w).float()
    grown = F.max_pool2d(spherical_pad(floor.reshape(1, 1, h, w), 1), 3, stride=1)
    return grown[0, 0].float()


def apply_floor(depth: torch.Tensor, floor: torch.Tensor | None) -> torch.Tensor:
    """max(D, F) for an (H, W) depth map (D itself without a floor)."""
    if floor is None:
        return depth
    return torch.maximum(depth, floor.to(device=depth.device, dtype=depth.dtype))


def outside_share(depth: torch.Tensor, points: torch.Tensor) -> float:
    """Share of ``points`` (M, 3) that the 2.5D light of ``depth`` (H, W) does not enclose
    (negative clearance, :func:`roomlight.fitting.inverse.repulsion.clearance`)."""
    from roomlight.fitting.inverse.repulsion import clearance

    if len(points) == 0:
        return 0.0
    return float((clearance(depth.detach().double().cpu(), torch.as_tensor(points).double()) < 0).double().mean())
