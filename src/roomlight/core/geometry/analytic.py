"""Closed-form depth maps of simple rooms, used as references in tests, demos and data checks."""

from __future__ import annotations

import torch

from roomlight.errors import ShapeError
from roomlight.core.geometry.equirect import pixel_directions

__all__ = ["box_distance", "box_room_depth"]


def box_distance(directions: torch.Tensor, box_min, box_max, origin=(0.0, 0.0, 0.0)) -> torch.Tensor:
    """Distance from ``origin`` (inside the box) along unit ``directions`` (*S, 3) to the box walls.

    For each axis the ray leaves the slab [min, max] at (bound - o) / d with the bound on the
    side the ray heads to; the exit distance is the smallest of the three.
    """
    d = directions
    o = torch.as_tensor(origin, dtype=d.dtype, device=d.device)
    lo = torch.as_tensor(box_min, dtype=d.dtype, device=d.device) - o
    hi = torch.as_tensor(box_max, dtype=d.dtype, device=d.device) - o
    if not ((lo < 0).all() and (hi > 0).all()):
        raise ShapeError(f"box_distance: origin {list(map(float, origin))} is not strictly inside the box")
    big = torch.finfo(d.dtype).max
    safe = torch.where(d.abs() > 1e-30, d, torch.full_like(d, 1e-30))
    t = torch.where(d > 0, hi / safe, torch.where(d < 0, lo / safe, torch.full_like(d, big)))
    return t.min(dim=-1).values


def box_room_depth(height: int, width: int, box_min, box_max, origin=(0.0, 0.0, 0.0),
                   dtype=torch.float32) -> torch.Tensor:
    """(H, W) radial depth panorama captured at ``origin`` inside an axis-aligned box room."""
    d = pixel_directions(height, width, dtype=torch.float64)
    return box_distance(d, box_min, box_max, origin).to(dtype)
