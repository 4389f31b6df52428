"""Changing the resolution of equirectangular panoramas."""

from __future__ import annotations

import torch
import torch.nn.functional as F

from roomlight.core.geometry.equirect import check_equirect_shape, pixel_directions, sample_equirect

__all__ = ["resize_panorama"]


def resize_panorama(pano: torch.Tensor, height: int) -> torch.Tensor:
    """Resample (B, C, H, W) panoramas to (B, C, height, 2 height).

    Integer down-scaling averages whole pixel blocks (each output pixel is the mean of the input
    pixels it covers, so HDR energy and small bright emitters are preserved); any other factor
    samples bilinearly on the sphere (seam- and pole-continuous).
    """
    b, c, h, w = pano.shape
    check_equirect_shape(h, w)
    if height == h:
        return pano
    if height < h and h % height == 0:
        k = h // height
        return F.avg_pool2d(pano, kernel_size=k, stride=k)
    d = pixel_directions(height, 2 * height, dtype=pano.dtype, device=pano.device)
    return sample_equirect(pano, d)
