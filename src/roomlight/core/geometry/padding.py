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
    if torch.is_grad_enabled() and x.requires_grad:
        # Training: a hand-written backward (see _SphericalPadFunction) instead of autograd
        # through eight slice assignments, which allocates and zero-fills a full-size gradient
        # buffer per assignment.
        return _SphericalPadFunction.apply(F.silu(x) if silu else x, pad)
    return _pad_forward(x, pad, silu)


def _pad_forward(x: torch.Tensor, pad: int, silu: bool = False) -> torch.Tensor:
    """The padding itself (no autograd bookkeeping); see :func:`spherical_pad`."""
    b, c, h, w = x.shape
    half = w // 2
    out = x.new_empty(b, c, h + 2 * pad, w + 2 * pad)
    core = out[:, :, :, pad:pad + w]
    if silu:
        src = core[:, :, pad:pad + h]
        torch.ops.aten.silu.out(x, out=src)
    else:
        src = x
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


def _pad_backward(grad: torch.Tensor, pad: int) -> torch.Tensor:
    """Adjoint of :func:`_pad_forward` (without SiLU): (B, C, H + 2p, W + 2p) -> (B, C, H, W).

    Every padded pixel is a copy of one interior pixel, so the gradient of an interior pixel
    is its own plus those of its copies. Folded in the reverse order of the forward pass: the
    wrapped columns onto the columns they copy (corners included, since the forward pass
    took them from rows already padded across the poles), then the pole rows onto the rows
    half a turn away, flipped.
    """
    b, c, hp, wp = grad.shape
    h, w = hp - 2 * pad, wp - 2 * pad
    half = w // 2
    core = grad[..., pad:pad + w].clone()          # (B, C, H + 2p, W), one copy
    core[..., w - pad:] += grad[..., :pad]          # out[..., :pad] = out[..., w:w + pad]
    core[..., :pad] += grad[..., pad + w:]          # out[..., pad + w:] = out[..., pad:2 pad]
    gx = core[:, :, pad:pad + h]                    # a view: the interior rows accumulate in place
    north, south = core[:, :, :pad], core[:, :, pad + h:]
    # core[:, :, :pad, :half] = north_src[..., half:] with north_src = rows [0, pad) flipped
    gx[:, :, :pad, half:] += north[..., :half].flip(2)
    gx[:, :, :pad, :half] += north[..., half:].flip(2)
    gx[:, :, h - pad:, half:] += south[..., :half].flip(2)
    gx[:, :, h - pad:, :half] += south[..., half:].flip(2)
    return gx.contiguous()


class _SphericalPadFunction(torch.autograd.Function):
    """:func:`spherical_pad` with its adjoint written out (same values, same gradients as the
    composition of slice copies; tested against autograd through a slow reference)."""

    @staticmethod
    def forward(ctx, x: torch.Tensor, pad: int) -> torch.Tensor:
        ctx.pad = pad
        return _pad_forward(x, pad)

    @staticmethod
    def backward(ctx, grad: torch.Tensor):
        return _pad_backward(grad, ctx.pad), None


class SphericalPad(torch.nn.Module):
    """Module form of :func:`spherical_pad`, placed before every unpadded 3x3 convolution."""

    def __init__(self, pad: int = 1):
        super().__init__()
        self.pad = pad

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return spherical_pad(x, self.pad)

    def extra_repr(self) -> str:
        return f"pad={self.pad}"
