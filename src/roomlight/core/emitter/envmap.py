"""The same radiance shown infinitely far away, as Mitsuba's ``envmap`` emitter.

Mitsuba's env map places texel columns at our pixel centres (phi = 2 pi (j + 0.5) / W) but its
rows run from pole to pole *inclusive* (theta = i pi / (He - 1)), and its ``data`` parameter
holds one extra wrap column on each side (He, W + 2, 3). A panorama in our convention is
therefore resampled in latitude to He = H + 1 rows and padded with wrap columns before it is
handed over; otherwise the env map would show a vertically shifted and stretched image.
"""

from __future__ import annotations

import math

import torch

from roomlight.core.geometry.equirect import check_equirect_shape, sample_equirect, uv_to_direction

__all__ = ["envmap_rows", "envmap_data"]


def envmap_rows(height: int) -> int:
    """Number of rows (pole to pole inclusive) used for an H-row panorama."""
    return height + 1


def envmap_data(radiance: torch.Tensor) -> torch.Tensor:
    """Resample (H, W, 3) radiance to the (H + 1, W + 2, 3) tensor Mitsuba's envmap stores.

    Differentiable in ``radiance`` (bilinear, seam- and pole-continuous).
    """
    h, w, c = radiance.shape
    check_equirect_shape(h, w, "env map")
    rows = envmap_rows(h)
    theta = torch.arange(rows, dtype=torch.float64, device=radiance.device) * (math.pi / (rows - 1))
    u = (torch.arange(w, dtype=torch.float64, device=radiance.device) + 0.5) / w
    vv, uu = torch.meshgrid(theta / math.pi, u, indexing="ij")
    dirs = uv_to_direction(uu, vv).to(radiance.dtype)
    pano = radiance.permute(2, 0, 1).unsqueeze(0)
    out = sample_equirect(pano, dirs)[0].permute(1, 2, 0)  # (rows, W, C)
    return torch.cat([out[:, -1:], out, out[:, :1]], dim=1).contiguous()
