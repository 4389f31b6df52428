"""A built-in example panorama: a furnished-looking box room with a window and a ceiling light.

It is defined analytically (exact radial depth from :func:`box_distance`, radiance from what
each ray hits), so it needs no data files and serves as the default input of ``roomlight
emitter``/``roomlight demo`` and in the README's worked example. Units: metres; radiance is
relative (the walls are ~0.1-0.5, the ceiling panel 30, the window 60-150).
"""

from __future__ import annotations

import torch

from roomlight.core.geometry.analytic import box_distance
from roomlight.core.geometry.equirect import pixel_directions

__all__ = ["EXAMPLE_ROOM", "example_room"]

#: Room box (metres) around the capture point at the origin (eye height 1.5 m above the floor).
EXAMPLE_ROOM = {"box_min": (-2.0, -1.5, -3.5), "box_max": (3.0, 1.3, 1.5)}


def example_room(height: int = 128, width: int | None = None, dtype=torch.float32) -> tuple[torch.Tensor, torch.Tensor]:
    """Radiance (H, W, 3) and radial depth (H, W) of the example room, seen from the origin."""
    width = width or 2 * height
    d = pixel_directions(height, width, dtype=torch.float64)
    lo, hi = EXAMPLE_ROOM["box_min"], EXAMPLE_ROOM["box_max"]
    t = box_distance(d, lo, hi)
    p = d * t[..., None]
    x, y, z = p.unbind(-1)
    eps = 1e-6
    rad = torch.empty(height, width, 3, dtype=torch.float64)
    # Walls: warm white paint with a gentle vertical gradient.
    rad[:] = torch.tensor([0.42, 0.38, 0.33], dtype=torch.float64)
    rad *= (0.8 + 0.2 * ((y - lo[1]) / (hi[1] - lo[1])))[..., None]
    floor = y <= lo[1] + eps
    # Wooden floor: planks along x with alternating tones.
    plank = (torch.floor(z / 0.25) % 2 == 0)
    wood = torch.where(plank[..., None], torch.tensor([0.30, 0.18, 0.09], dtype=torch.float64),
                       torch.tensor([0.24, 0.14, 0.07], dtype=torch.float64))
    rad = torch.where(floor[..., None], wood, rad)
    ceiling = y >= hi[1] - eps
    rad = torch.where(ceiling[..., None], torch.tensor([0.5, 0.5, 0.5], dtype=torch.float64), rad)
    # Ceiling light panel (1.0 x 0.6 m) above and in front of the capture point.
    panel = ceiling & ((x - 0.5).abs() < 0.5) & ((z + 1.2).abs() < 0.3)
    rad = torch.where(panel[..., None], torch.tensor([30.0, 28.0, 24.0], dtype=torch.float64), rad)
    # Window on the +x wall with a blue-ish sky and a brighter region near its top.
    wall_x = x >= hi[0] - eps
    window = wall_x & ((z + 1.0).abs() < 0.9) & (y > -0.4) & (y < 1.0)
    sky = torch.stack([60.0 + 40.0 * (y - 0.3), 80.0 + 40.0 * (y - 0.3), 120.0 + 30.0 * (y - 0.3)], -1)
    rad = torch.where(window[..., None], sky, rad)
    # A dark door on the -z wall and a red sofa-coloured band low on the +z wall.
    door = (z <= lo[2] + eps) & ((x + 1.0).abs() < 0.45) & (y < 0.6)
    rad = torch.where(door[..., None], torch.tensor([0.12, 0.08, 0.05], dtype=torch.float64), rad)
    sofa = (z >= hi[2] - eps) & (y < -0.9) & (x.abs() < 1.2)
    rad = torch.where(sofa[..., None], torch.tensor([0.35, 0.06, 0.05], dtype=torch.float64), rad)
    return rad.to(dtype), t.to(dtype)
