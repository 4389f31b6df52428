"""What a view shows, lifted onto the panorama around its camera: the view encoder's input.

A photograph (or a perspective crop of a panorama) with per-pixel radiance and camera-frame
points is turned into a *partial panorama* at the prior's resolution, in the room frame whose
origin is the camera centre:

- each valid view pixel is a sample of the direction d = R p / |p| (R: camera -> room rotation,
  the camera's pitch and roll; p: the camera-frame point the pixel sees);
- it falls into the panorama pixel whose cell contains d (the equirectangular convention of
  :mod:`roomlight.core.geometry.equirect`);
- a panorama pixel's radiance is the *mean* of the linear radiance of its samples, and its log
  depth the mean of their log radial depths |p|; pixels without a sample are unseen.

Averaging (a box filter over the cell) rather than point-sampling the view keeps the result
independent of the view's resolution once the view is finer than the panorama, which is why
views are first brought to about three pixels per panorama cell (:func:`lift_resolution`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import torch

from roomlight.core.geometry.equirect import direction_to_uv

__all__ = ["PartialPanorama", "lift_view", "lift_resolution", "SAMPLES_PER_CELL"]

#: View pixels per panorama cell along a line that :func:`lift_resolution` aims for near the centre
#: of the view (a perspective view's pixels subtend less at its edges, so there they are more).
SAMPLES_PER_CELL = 3.0


@dataclass
class PartialPanorama:
    """A view lifted onto the sphere around its camera (room frame).

    Attributes:
        radiance: (3, H, W) float32 mean linear radiance of the samples in each cell (0 where unseen).
        log_depth: (1, H, W) float32 mean log radial depth (log metres; 0 where unseen).
        count: (H, W) float32 number of view samples in each cell.
    """

    radiance: torch.Tensor
    log_depth: torch.Tensor
    count: torch.Tensor

    @property
    def seen(self) -> torch.Tensor:
        """(H, W) bool: cells with at least one sample."""
        return self.count > 0

    @property
    def seen_fraction(self) -> float:
        """Share of the panorama's cells that the view covers (unweighted by solid angle)."""
        return float(self.seen.float().mean())


def lift_view(points: torch.Tensor, radiance: torch.Tensor, rotation, resolution: tuple[int, int],
              valid: torch.Tensor | None = None) -> PartialPanorama:
    """Lift a view's samples onto the equirectangular grid (module docstring).

    Args:
        points: (..., 3) camera-frame points seen by the view's pixels, metres (x right, y up,
            the camera looking along -z); the radial depth of a sample is ``|p|``.
        radiance: (..., 3) their linear radiance.
        rotation: (3, 3) camera -> room rotation.
        resolution: (H, W) of the panorama, W = 2H.
        valid: (...) bool, the samples to use (e.g. the background of a photo); default all with
            finite points at a positive distance.
    Returns:
        the :class:`PartialPanorama`.
    """
    h, w = (int(v) for v in resolution)
    p = torch.as_tensor(points, dtype=torch.float64).reshape(-1, 3)
    rad = torch.as_tensor(radiance, dtype=torch.float64).reshape(-1, 3)
    r = p.norm(dim=-1)
    keep = torch.isfinite(p).all(-1) & (r > 0) & torch.isfinite(rad).all(-1)
    if valid is not None:
        keep &= torch.as_tensor(valid, dtype=torch.bool).reshape(-1)
    p, rad, r = p[keep], rad[keep], r[keep]
    R = torch.as_tensor(rotation, dtype=torch.float64).reshape(3, 3)
    u, v = direction_to_uv(p @ R.T)
    col = (u * w).floor().long().clamp_(0, w - 1)
    row = (v * h).floor().long().clamp_(0, h - 1)
    cell = row * w + col
    count = torch.bincount(cell, minlength=h * w).to(torch.float64)
    sums = torch.zeros(h * w, 4, dtype=torch.float64)
    sums.index_add_(0, cell, torch.cat([rad.clamp_min(0.0), torch.log(r)[:, None]], dim=1))
    mean = sums / count.clamp_min(1.0)[:, None]
    mean = mean.T.reshape(4, h, w).float()
    return PartialPanorama(mean[:3].contiguous(), mean[3:].contiguous(), count.reshape(h, w).float())


def lift_resolution(fov_deg: float, aspect: float, pano_width: int,
                    samples_per_cell: float = SAMPLES_PER_CELL) -> tuple[int, int]:
    """(height, width) of a view of horizontal field of view ``fov_deg`` and width/height
    ``aspect`` whose central pixels are ``samples_per_cell`` times finer than a cell of a panorama
    ``pano_width`` pixels wide."""
    cell = 2.0 * math.pi / pano_width
    f_pix = cell / samples_per_cell                       # angle of one central view pixel
    width = 2.0 * math.tan(math.radians(fov_deg) / 2.0) / f_pix
    width = max(4, int(math.ceil(width)))
    return max(4, int(round(width / aspect))), width
