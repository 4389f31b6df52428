"""The equirectangular convention (docs/conventions.md); this module is the only place that defines it.

A panorama is H x W with W = 2H. Pixel (i, j) has its centre at u = (j + 0.5) / W,
v = (i + 0.5) / H; azimuth phi = 2 pi u, polar angle theta = pi v, and the direction is

    omega(u, v) = (sin(phi) sin(theta), cos(theta), -cos(phi) sin(theta))

so **y is up**, row 0 is the zenith, u = 0 looks along -z, u = 0.25 along +x and the image
centre (u = 0.5) along +z. This matches Mitsuba's ``envmap`` horizontally.

All functions take and return torch tensors and are differentiable where that makes sense.
"""

from __future__ import annotations

import math

import torch

from roomlight.errors import ShapeError

__all__ = [
    "check_equirect_shape",
    "pixel_uv",
    "uv_to_direction",
    "direction_to_uv",
    "pixel_directions",
    "pixel_solid_angles",
    "latitude_channels",
    "sample_equirect",
]


def check_equirect_shape(height: int, width: int, what: str = "panorama") -> None:
    """Raise :class:`ShapeError` unless ``width == 2 * height`` (and both are positive)."""
    if height <= 0 or width != 2 * height:
        raise ShapeError(
            f"{what}: expected an equirectangular image with width = 2 x height, "
            f"got {height}x{width} (H x W); resample it to {height}x{2 * height} first"
        )


def pixel_uv(height: int, width: int, dtype=torch.float32, device=None) -> torch.Tensor:
    """Pixel-centre texture coordinates.

    Returns:
        (H, W, 2) tensor of (u, v) in (0, 1), u along columns, v along rows.
    """
    u = (torch.arange(width, dtype=dtype, device=device) + 0.5) / width
    v = (torch.arange(height, dtype=dtype, device=device) + 0.5) / height
    vv, uu = torch.meshgrid(v, u, indexing="ij")
    return torch.stack([uu, vv], dim=-1)


def uv_to_direction(u: torch.Tensor, v: torch.Tensor) -> torch.Tensor:
    """Unit direction for texture coordinates (any matching shapes ``S``) -> (*S, 3)."""
    phi = 2.0 * math.pi * u
    theta = math.pi * v
    st = torch.sin(theta)
    return torch.stack([torch.sin(phi) * st, torch.cos(theta), -torch.cos(phi) * st], dim=-1)


def direction_to_uv(d: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """Texture coordinates of arbitrary (not necessarily unit) directions (*S, 3).

    Returns (u, v) with u in [0, 1) and v in [0, 1]. theta is computed with atan2 so that it is
    accurate near the poles (acos loses precision there).
    """
    x, y, z = d.unbind(-1)
    u = torch.remainder(torch.atan2(x, -z) / (2.0 * math.pi), 1.0)
    v = torch.atan2(torch.sqrt(x * x + z * z), y) / math.pi
    return u, v


def pixel_directions(height: int, width: int, dtype=torch.float32, device=None) -> torch.Tensor:
    """(H, W, 3) unit directions through the pixel centres."""
    uv = pixel_uv(height, width, dtype=torch.float64, device=device)
    return uv_to_direction(uv[..., 0], uv[..., 1]).to(dtype)


def pixel_solid_angles(height: int, width: int, dtype=torch.float32, device=None) -> torch.Tensor:
    """(H, W) exact solid angle (steradians) of each pixel's spherical cell; they sum to 4 pi.

    A row spanning theta in [i pi/H, (i+1) pi/H] covers 2 pi (cos theta_0 - cos theta_1) sr,
    split equally among its W pixels.
    """
    edges = torch.arange(height + 1, dtype=torch.float64, device=device) * (math.pi / height)
    row = (2.0 * math.pi / width) * (torch.cos(edges[:-1]) - torch.cos(edges[1:]))
    return row[:, None].expand(height, width).to(dtype).contiguous()


def latitude_channels(height: int, width: int, dtype=torch.float32, device=None) -> torch.Tensor:
    """(2, H, W) channels (cos theta, sin theta) at pixel centres, the network's latitude input."""
    theta = (torch.arange(height, dtype=torch.float64, device=device) + 0.5) * (math.pi / height)
    ch = torch.stack([torch.cos(theta), torch.sin(theta)])[:, :, None].expand(2, height, width)
    return ch.to(dtype).contiguous()


def sample_equirect(pano: torch.Tensor, directions: torch.Tensor, batched: bool = False) -> torch.Tensor:
    """Bilinearly sample panoramas in arbitrary directions.

    Interpolation is continuous across the longitude seam and across the poles (the image is
    spherically padded by one pixel first), so the result has no seam artefacts.

    Args:
        pano: (B, C, H, W) panoramas (W = 2H).
        directions: (*S, 3) directions shared by the whole batch or, with ``batched=True``,
            (B, *S, 3) directions per panorama (need not be unit length), in the panorama's frame.
        batched: whether ``directions`` carries a leading batch dimension. It is explicit because
            a shape such as (16, 32, 3) could be either.
    Returns:
        (B, C, *S) samples.
    """
    from roomlight.core.geometry.padding import spherical_pad

    if pano.dim() != 4:
        raise ShapeError(f"sample_equirect: expected pano of shape (B, C, H, W), got {tuple(pano.shape)}")
    b, c, h, w = pano.shape
    check_equirect_shape(h, w)
    if batched:
        if directions.shape[0] != b:
            raise ShapeError(f"sample_equirect: {b} panoramas but directions for {directions.shape[0]}")
        dirs = directions
    else:
        dirs = directions.unsqueeze(0).expand(b, *directions.shape)
    spatial = dirs.shape[1:-1]
    u, v = direction_to_uv(dirs.reshape(b, -1, 3).to(pano.dtype))
    padded = spherical_pad(pano, 1)
    # Pixel coordinates in the padded image (pixel centres at integers, align_corners=True).
    x = u * w - 0.5 + 1.0
    y = v * h - 0.5 + 1.0
    gx = x / (w + 1) * 2.0 - 1.0
    gy = y / (h + 1) * 2.0 - 1.0
    grid = torch.stack([gx, gy], dim=-1).unsqueeze(1)  # (B, 1, N, 2)
    out = torch.nn.functional.grid_sample(
        padded, grid, mode="bilinear", padding_mode="border", align_corners=True
    )  # (B, C, 1, N)
    return out[:, :, 0].reshape(b, c, *spatial)
