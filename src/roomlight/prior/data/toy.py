"""Toy panoramas: random box rooms with analytic depth, for tests, smoke runs and examples.

Not a substitute for the procedural rooms of ``roomlight synth`` (no path tracing, no indirect
light, no furniture), but instant and dependency-free: each panorama is an axis-aligned box room
seen from a random interior point, with exact radial depth, tinted walls with a smooth shading
gradient, a plank floor, and one or two emitters (a ceiling panel and/or a window) whose radiance
is 30-300x the walls'. Deterministic per seed.
"""

from __future__ import annotations

from pathlib import Path

import torch

from roomlight.core.geometry.analytic import box_distance
from roomlight.core.geometry.equirect import pixel_directions

__all__ = ["toy_panorama", "write_toy_dataset"]


def toy_panorama(seed: int, height: int = 32) -> tuple[torch.Tensor, torch.Tensor]:
    """Radiance (H, 2H, 3) float32 linear and radial depth (H, 2H) float32 in metres."""
    g = torch.Generator().manual_seed(int(seed))

    def u(lo, hi, n=None):
        shape = () if n is None else (n,)
        return lo + (hi - lo) * torch.rand(shape, generator=g, dtype=torch.float64)

    w = 2 * height
    size = torch.stack([u(2.5, 8.0), u(2.4, 3.5), u(2.5, 8.0)])  # x, y (height), z extents
    eye = torch.stack([u(0.25, 0.75) * size[0], u(1.0, 1.7), u(0.25, 0.75) * size[2]])
    lo, hi = (-eye).tolist(), (size - eye).tolist()
    d = pixel_directions(height, w, dtype=torch.float64)
    t = box_distance(d, lo, hi)
    p = d * t[..., None]
    x, y, z = p.unbind(-1)
    eps = 1e-6
    wall = u(0.2, 0.7, 3) * torch.tensor([1.0, 0.95, 0.85], dtype=torch.float64)
    shade = 0.7 + 0.3 * (y - lo[1]) / (hi[1] - lo[1])
    rad = wall.expand(height, w, 3) * shade[..., None]
    # A second wall colour on the two x walls so the room is not rotationally uniform.
    xwall = (x <= lo[0] + eps) | (x >= hi[0] - eps)
    rad = torch.where(xwall[..., None], rad * u(0.5, 1.2, 3), rad)
    floor = y <= lo[1] + eps
    plank = torch.floor(z / u(0.15, 0.4)) % 2 == 0
    wood = u(0.1, 0.35, 3) * torch.tensor([1.0, 0.6, 0.3], dtype=torch.float64)
    rad = torch.where(floor[..., None], torch.where(plank[..., None], wood, 0.8 * wood), rad)
    ceiling = y >= hi[1] - eps
    rad = torch.where(ceiling[..., None], torch.full_like(rad, float(u(0.4, 0.8))), rad)
    kind = int(torch.randint(0, 3, (), generator=g))  # 0 panel, 1 window, 2 both
    if kind in (0, 2):
        cx, cz, hx, hz = u(-0.5, 0.5) + 0.0, u(-0.5, 0.5), u(0.3, 0.8), u(0.3, 0.8)
        panel = ceiling & ((x - cx).abs() < hx) & ((z - cz).abs() < hz)
        rad = torch.where(panel[..., None], u(20.0, 60.0) * torch.tensor([1.0, 0.95, 0.85], dtype=torch.float64), rad)
    if kind in (1, 2):
        on_x = x >= hi[0] - eps
        wz, wy = u(lo[2] + 0.5, hi[2] - 0.5), u(-0.2, 0.6)
        window = on_x & ((z - wz).abs() < u(0.4, 1.0)) & ((y - wy).abs() < u(0.4, 0.7))
        sky = u(40.0, 150.0) * torch.tensor([0.7, 0.85, 1.0], dtype=torch.float64)
        rad = torch.where(window[..., None], sky * (1.0 + 0.3 * (y - wy))[..., None].clamp_min(0.5), rad)
    return rad.float(), t.float()


def write_toy_dataset(out_dir: str | Path, n: int, height: int = 32, seed: int = 0,
                      calibrate: bool = True) -> list[Path]:
    """Write ``n`` toy panoramas as roomlight EXRs (R, G, B half, Z float) into ``out_dir``.

    File ``toy-{seed + i:05d}.exr`` holds :func:`toy_panorama` ``(seed + i)``, exposure
    calibrated when ``calibrate`` (factor in the metadata). Returns the paths.
    """
    from roomlight.core.io import exposure_calibrate, write_panorama

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    for i in range(n):
        rad, depth = toy_panorama(seed + i, height)
        meta = {"source": "roomlight.prior.data.toy", "seed": seed + i}
        if calibrate:
            rad, factor = exposure_calibrate(rad.numpy())
            meta["exposure_factor"] = factor
        p = out / f"toy-{seed + i:05d}.exr"
        write_panorama(p, (rad, depth.numpy()), metadata=meta)
        paths.append(p)
    return paths
