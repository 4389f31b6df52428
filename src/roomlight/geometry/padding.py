"""Spherical padding for equirectangular feature maps (paper §3.2, DESIGN.md §3).

Longitude wraps around; beyond each pole the neighbourhood of a pixel is the same latitude
band half a turn away, so the boundary rows are flipped vertically and rolled by W/2.
"""

from __future__ import annotations

import torch
import torch.nn.functional as F

from roomlight.errors import ShapeError

__all__ = ["spherical_pad", "SphericalPad"]


def spherical_pad(x: torch.Tensor, pad: int = 1) -> torch.Tensor:
    """Pad (B, C, H, W) maps by ``pad`` pixels on every side, following the sphere.

    Returns (B, C, H + 2 pad, W + 2 pad). Requires an even W and pad <= H, pad <= W.
    Padded row -k (k = 1..pad) at column j equals row k-1 at column (j + W/2) mod W; the south
    pole is the mirror image; columns wrap. Corners are consistent with both rules.
    """
    if pad == 0:
        return x
    if x.dim() != 4:
        raise ShapeError(f"spherical_pad: expected (B, C, H, W), got shape {tuple(x.shape)}")
    h, w = x.shape[-2:]
    if w % 2 or pad > h or pad > w:
        raise ShapeError(f"spherical_pad: need even width and pad <= H, W; got H={h}, W={w}, pad={pad}")
    half = w // 2
    top = torch.roll(torch.flip(x[:, :, :pad], dims=[2]), shifts=half, dims=3)
    bottom = torch.roll(torch.flip(x[:, :, -pad:], dims=[2]), shifts=half, dims=3)
    y = torch.cat([top, x, bottom], dim=2)
    return F.pad(y, (pad, pad, 0, 0), mode="circular")


class SphericalPad(torch.nn.Module):
    """Module form of :func:`spherical_pad`, placed before every unpadded 3x3 convolution."""

    def __init__(self, pad: int = 1):
        super().__init__()
        self.pad = pad

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return spherical_pad(x, self.pad)

    def extra_repr(self) -> str:
        return f"pad={self.pad}"
