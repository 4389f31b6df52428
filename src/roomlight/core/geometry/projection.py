"""Perspective (gnomonic) views cut from a panorama, and pasted back.

Camera frame: a view looks along ``forward``; image x grows to the right
(``right = forward x up``) and image y grows downwards. ``fov_deg`` is the horizontal field
of view (Mitsuba's default ``fov_axis='x'``), so a render from Mitsuba's ``perspective``
sensor built with ``look_at(origin, origin + forward, up)`` shows the same rays.
"""

from __future__ import annotations

import math

import torch

from roomlight.core.geometry.equirect import pixel_directions, sample_equirect
from roomlight.errors import ShapeError

__all__ = ["camera_basis", "perspective_directions", "panorama_to_perspective", "perspective_to_panorama"]


def _vec(x, dtype) -> torch.Tensor:
    return torch.as_tensor(x, dtype=dtype).reshape(3)


def camera_basis(forward, up=(0.0, 1.0, 0.0), dtype=torch.float64) -> torch.Tensor:
    """(3, 3) matrix whose rows are (right, up, forward) unit vectors of a view."""
    f = _vec(forward, dtype)
    f = f / f.norm()
    u = _vec(up, dtype)
    r = torch.linalg.cross(f, u)
    if r.norm() < 1e-9:
        raise ShapeError(f"camera_basis: forward {f.tolist()} is parallel to up {u.tolist()}; pick another up vector")
    r = r / r.norm()
    u = torch.linalg.cross(r, f)
    return torch.stack([r, u, f])


def perspective_directions(height: int, width: int, fov_deg: float, forward=(0.0, 0.0, -1.0),
                           up=(0.0, 1.0, 0.0), dtype=torch.float32) -> torch.Tensor:
    """(H, W, 3) unit directions through the pixel centres of a pinhole view.

    ``fov_deg`` is the horizontal field of view in degrees; pixels are square.
    """
    if not 0.0 < fov_deg < 180.0:
        raise ShapeError(f"perspective view: fov must be in (0, 180) degrees, got {fov_deg}")
    basis = camera_basis(forward, up)
    t = math.tan(math.radians(fov_deg) / 2.0)
    x = ((torch.arange(width, dtype=torch.float64) + 0.5) / width * 2.0 - 1.0) * t
    y = ((torch.arange(height, dtype=torch.float64) + 0.5) / height * 2.0 - 1.0) * t * height / width
    yy, xx = torch.meshgrid(y, x, indexing="ij")
    d = xx[..., None] * basis[0] - yy[..., None] * basis[1] + basis[2]
    return (d / d.norm(dim=-1, keepdim=True)).to(dtype)


def panorama_to_perspective(pano: torch.Tensor, height: int, width: int, fov_deg: float,
                            forward=(0.0, 0.0, -1.0), up=(0.0, 1.0, 0.0)) -> torch.Tensor:
    """Resample a gnomonic view from panoramas: (B, C, H, W) -> (B, C, height, width)."""
    dirs = perspective_directions(height, width, fov_deg, forward, up, dtype=pano.dtype).to(pano.device)
    return sample_equirect(pano, dirs)


def perspective_to_panorama(view: torch.Tensor, pano_height: int, fov_deg: float,
                            forward=(0.0, 0.0, -1.0), up=(0.0, 1.0, 0.0)) -> tuple[torch.Tensor, torch.Tensor]:
    """Project a gnomonic view back onto the panorama (inverse of :func:`panorama_to_perspective`).

    Args:
        view: (B, C, h, w) perspective images.
        pano_height: H of the target panorama (its width is 2H).
    Returns:
        (pano, mask): (B, C, H, 2H) values bilinearly sampled from the view where the pixel's
        direction falls inside the view, zeros elsewhere; mask is (H, 2H) bool.
    """
    b, c, h, w = view.shape
    basis = camera_basis(forward, up, dtype=view.dtype).to(view.device)
    dirs = pixel_directions(pano_height, 2 * pano_height, dtype=view.dtype, device=view.device)
    local = dirs @ basis.T  # (H, W, 3) in (right, up, forward) coordinates
    t = math.tan(math.radians(fov_deg) / 2.0)
    front = local[..., 2] > 1e-6
    z = torch.where(front, local[..., 2], torch.ones_like(local[..., 2]))
    x = local[..., 0] / z / t                       # in [-1, 1] across the view's width
    y = -local[..., 1] / z / (t * h / w)           # in [-1, 1] across its height
    mask = front & (x.abs() <= 1.0) & (y.abs() <= 1.0)
    grid = torch.stack([x, y], dim=-1).unsqueeze(0).expand(b, -1, -1, -1)
    out = torch.nn.functional.grid_sample(view, grid, mode="bilinear", padding_mode="border",
                                          align_corners=False)
    return out * mask.to(view.dtype), mask


