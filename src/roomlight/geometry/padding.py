"""Spherical padding for equirectangular feature maps (paper §3.2; docs/conventions.md).

Longitude wraps around; beyond each pole the neighbourhood of a pixel is the same latitude
band half a turn away, so the boundary rows are flipped vertically and rolled by W/2.
"""

from __future__ import annotations

import torch
import torch.nn.functional as F

from roomlight.errors import ShapeError

__all__ = ["spherical_pad", "SphericalPad"]


def spherical_pad(x: torch.Tensor, pad: int = 1, silu: bool = False) -> torch.Tensor:
    """Pad (B, C, H, W) maps by ``pad`` pixels on every side, following the sphere.

    Returns (B, C, H + 2 pad, W + 2 pad). Requires an even W and pad <= H, pad <= W.
    Padded row -k (k = 1..pad) at column j equals row k-1 at column (j + W/2) mod W; the south
    pole is the mirror image; columns wrap. Corners are consistent with both rules.

    The output is allocated once and filled by slices (the interior is copied once), which is
    several times cheaper than chaining flips, rolls, concatenations and a circular pad.

    ``silu=True`` pads SiLU(x) instead of x. Every padded conv of the VAE follows a SiLU, and
    when no gradient is needed the activation is written straight into the padded buffer,
    saving one full pass over the map and one allocation (inference and latent fitting
    without gradients); with autograd it is the plain composition.
    """
    if pad == 0:
        return x
    if x.dim() != 4:
        raise ShapeError(f"spherical_pad: expected (B, C, H, W), got shape {tuple(x.shape)}")
    b, c, h, w = x.shape
    if w % 2 or pad > h or pad > w:
        raise ShapeError(f"spherical_pad: need even width and pad <= H, W; got H={h}, W={w}, pad={pad}")
    half = w // 2
    out = x.new_empty(b, c, h + 2 * pad, w + 2 * pad)
    core = out[:, :, :, pad:pad + w]
    if silu and not (torch.is_grad_enabled() and x.requires_grad):
        src = core[:, :, pad:pad + h]
        torch.ops.aten.silu.out(x, out=src)
    else:
        src = F.silu(x) if silu else x
        core[:, :, pad:pad + h] = src
    # across each pole: the boundary rows mirrored, half a turn away (column j <- j + W/2)
    north = src[:, :, :pad].flip(2)
    south = src[:, :, -pad:].flip(2)
    core[:, :, :pad, :half] = north[..., half:]
    core[:, :, :pad, half:] = north[..., :half]
    core[:, :, pad + h:, :half] = south[..., half:]
    core[:, :, pad + h:, half:] = south[..., :half]
    # longitude wrap, taken from the already-filled columns so the corners agree
    out[..., :pad] = out[..., w:w + pad]
    out[..., pad + w:] = out[..., pad:2 * pad]
    return out


class SphericalPad(torch.nn.Module):
    """Module form of :func:`spherical_pad`, placed before every unpadded 3x3 convolution."""

    def __init__(self, pad: int = 1):
        super().__init__()
        self.pad = pad

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return spherical_pad(x, self.pad)

    def extra_repr(self) -> str:
        return f"pad={self.pad}"
