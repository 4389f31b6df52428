"""3-D rotations of panoramas (used for the tilt augmentation and for re-orienting captures)."""

from __future__ import annotations

import math

import torch

from roomlight.core.geometry.equirect import pixel_directions, sample_equirect

__all__ = ["rotation_matrix", "rotate_panorama"]


def rotation_matrix(axis, angle_rad: float, dtype=torch.float64) -> torch.Tensor:
    """(3, 3) right-handed rotation by ``angle_rad`` about ``axis`` ('x', 'y', 'z' or a 3-vector)."""
    if isinstance(axis, str):
        axis = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}[axis.lower()]
    a = torch.as_tensor(axis, dtype=dtype).reshape(3)
    a = a / a.norm()
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    k = torch.tensor([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]], dtype=dtype)
    return torch.eye(3, dtype=dtype) * c + s * k + (1.0 - c) * torch.outer(a, a)


def rotate_panorama(pano: torch.Tensor, rotation: torch.Tensor) -> torch.Tensor:
    """Rotate the spherical content of panoramas by ``rotation``.

    The value seen in direction d after the rotation is the value that was seen in direction
    R^T d before it, i.e. a light at direction a moves to R a. Radial depth is a scalar field on
    the sphere, so depth maps rotate with the same call.

    Args:
        pano: (B, C, H, W) panoramas.
        rotation: (3, 3) or (B, 3, 3) rotation matrices.
    Returns:
        (B, C, H, W) resampled panoramas (bilinear, seam- and pole-continuous).
    """
    b, _, h, w = pano.shape
    d = pixel_directions(h, w, dtype=pano.dtype, device=pano.device)  # (H, W, 3)
    r = rotation.to(pano.dtype).to(pano.device)
    if r.dim() == 2:
        src = d @ r  # rows: (R^T d)^T = d^T R
        return sample_equirect(pano, src)
    src = torch.einsum("hwi,bij->bhwj", d, r)
    return sample_equirect(pano, src, batched=True)
