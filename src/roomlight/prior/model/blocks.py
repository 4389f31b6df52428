"""Building blocks of the panoramic VAE (paper §3.2; docs/model.md).

Every 3x3 convolution is *unpadded* and preceded by spherical padding, so features wrap in
longitude and continue across the poles instead of seeing zeros. Sub-module names (``conv``,
``norm1``, ``conv1.conv``, ``to_scale_shift`` ...) are chosen to coincide with the authors'
state_dict layout inside each block; only the top-level prefixes differ (see
:mod:`roomlight.prior.model.convert`).

All feature maps are (B, C, H, W) equirectangular with even W.
"""

from __future__ import annotations

import torch
import torch.nn.functional as F
from torch import nn

from roomlight.core.geometry.padding import spherical_pad

__all__ = [
    "SphericalConv2d",
    "ResBlock",
    "AdaGN",
    "AdaGNResBlock",
    "Downsample",
    "Upsample",
]


class SphericalConv2d(nn.Module):
    """3x3 convolution with one pixel of spherical padding.

    (B, C_in, H, W) -> (B, C_out, H / stride, W / stride). With stride 2 this is the encoder's
    downsampling conv: output pixel (i, j) sees input rows 2i-1..2i+1, so rolling the input by an
    even number of columns 2k rolls the output by k.
    """

    def __init__(self, in_channels: int, out_channels: int, stride: int = 1):
        super().__init__()
        self.conv = nn.Conv2d(in_channels, out_channels, kernel_size=3, stride=stride, padding=0)

    def forward(self, x: torch.Tensor, silu: bool = False) -> torch.Tensor:
        """conv(pad(x)), or conv(pad(SiLU(x))) with ``silu`` (fused, see :func:`spherical_pad`)."""
        return self.conv(spherical_pad(x, 1, silu=silu))


class Downsample(SphericalConv2d):
    """Stride-2 spherically padded 3x3 conv: (B, C_in, H, W) -> (B, C_out, H/2, W/2)."""

    def __init__(self, in_channels: int, out_channels: int):
        super().__init__(in_channels, out_channels, stride=2)


class Upsample(nn.Module):
    """Nearest-neighbour x2 upsampling followed by a padded 3x3 conv.

    (B, C_in, H, W) -> (B, C_out, 2H, 2W). Nearest (not bilinear) keeps the operation exactly
    equivariant to longitude rolls and matches the authors' network.

    Computed without materialising the upsampled map: after a nearest x2 upsampling each
    output pixel's 3x3 window covers only 2x2 distinct input pixels, so each of the four output
    phases (row parity a, column parity b) is a 2x2 convolution of the (spherically padded)
    low-resolution input with the 3x3 kernel's rows and columns summed pairwise. That is 16
    multiply-adds per input pixel instead of 36, and the padding happens at low resolution
    (spherical padding commutes with nearest upsampling when W is even). The weights are the
    same 3x3 ``conv.conv.weight``; :meth:`reference_forward` is the literal definition.
    """

    def __init__(self, in_channels: int, out_channels: int):
        super().__init__()
        self.conv = SphericalConv2d(in_channels, out_channels)

    def reference_forward(self, x: torch.Tensor) -> torch.Tensor:
        """The definition: upsample, pad, 3x3 conv (slower; used by tests)."""
        return self.conv(F.interpolate(x, scale_factor=2.0, mode="nearest"))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        b, _, h, w = x.shape
        if w % 2:  # spherical padding of the low-resolution map needs an even width
            return self.reference_forward(x)
        weight, bias = self.conv.conv.weight, self.conv.conv.bias
        out_ch = weight.shape[0]
        # Rows of the window for output row 2i + a: a = 0 -> input rows (i-1, i) with kernel rows
        # (0, 1 + 2); a = 1 -> input rows (i, i+1) with kernel rows (0 + 1, 2). Same for columns.
        rows = (torch.stack([weight[:, :, 0], weight[:, :, 1] + weight[:, :, 2]], 2),
                torch.stack([weight[:, :, 0] + weight[:, :, 1], weight[:, :, 2]], 2))
        kernels = [torch.stack(cols, -1) for r in rows
                   for cols in ((r[..., 0], r[..., 1] + r[..., 2]), (r[..., 0] + r[..., 1], r[..., 2]))]
        y = F.conv2d(spherical_pad(x, 1), torch.cat(kernels, 0), bias.repeat(4) if bias is not None else None)
        y = y.view(b, 2, 2, out_ch, h + 1, w + 1)  # (B, a, b, C_out, H+1, W+1)
        # phase (a, b) at input pixel (i, j) is the 2x2 window starting at padded (i + a, j + b)
        out = y.new_empty(b, out_ch, h, 2, w, 2)
        for a in (0, 1):
            for c in (0, 1):
                out[:, :, :, a, :, c] = y[:, a, c, :, a:a + h, c:c + w]
        return out.view(b, out_ch, 2 * h, 2 * w)


class ResBlock(nn.Module):
    """Pre-activation residual block: x + conv2(SiLU(GN2(conv1(SiLU(GN1(x)))))).

    Channel count is unchanged, so the skip is the identity. (B, C, H, W) -> (B, C, H, W).
    Norms are affine GroupNorms with ``eps`` (1e-6 in the authors' network). Modules are
    registered norm1, norm2, conv1, conv2 to reproduce the authors' state_dict order.
    """

    def __init__(self, channels: int, groups: int, eps: float = 1e-6):
        super().__init__()
        self.norm1 = nn.GroupNorm(groups, channels, eps=eps)
        self.norm2 = nn.GroupNorm(groups, channels, eps=eps)
        self.conv1 = SphericalConv2d(channels, channels)
        self.conv2 = SphericalConv2d(channels, channels)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        h = self.conv1(self.norm1(x), silu=True)
        h = self.conv2(self.norm2(h), silu=True)
        # in place: h is a fresh conv output that no backward formula needs
        return h.add_(x)


class AdaGN(nn.Module):
    """Adaptive GroupNorm: GN(x) * (1 + scale(z)) + shift(z).

    The GroupNorm has no affine parameters; ``to_scale_shift`` is a Linear(latent_dim, 2 C) whose
    output is (scale || shift). It is zero-initialised, so a fresh AdaGN is exactly a plain
    GroupNorm and the latent's influence is learnt from there (as in the authors' network).

    forward(x: (B, C, H, W), z: (B, latent_dim)) -> (B, C, H, W).
    """

    def __init__(self, channels: int, latent_dim: int, groups: int, eps: float = 1e-6):
        super().__init__()
        self.channels = channels
        self.groups = groups
        self.eps = eps
        self.to_scale_shift = nn.Linear(latent_dim, 2 * channels)
        nn.init.zeros_(self.to_scale_shift.weight)
        nn.init.zeros_(self.to_scale_shift.bias)

    def forward(self, x: torch.Tensor, z: torch.Tensor) -> torch.Tensor:
        b, c, h, w = x.shape
        scale, shift = self.to_scale_shift(z).chunk(2, dim=1)
        # The per-sample affine is folded into one GroupNorm call: normalising (1, B C, H, W)
        # in B G groups is GN of each sample in G groups, and its per-channel weight/bias of
        # length B C are exactly (1 + scale(z_b), shift(z_b)). Saves two passes over the map.
        y = F.group_norm(x.reshape(1, b * c, h, w), b * self.groups,
                         (1.0 + scale).reshape(-1), shift.reshape(-1), self.eps)
        return y.view(b, c, h, w)

    def extra_repr(self) -> str:
        return f"channels={self.channels}, groups={self.groups}, eps={self.eps}"


class AdaGNResBlock(nn.Module):
    """:class:`ResBlock` whose two norms are :class:`AdaGN` conditioned on the latent z.

    forward(x: (B, C, H, W), z: (B, latent_dim)) -> (B, C, H, W).
    """

    def __init__(self, channels: int, latent_dim: int, groups: int, eps: float = 1e-6):
        super().__init__()
        self.norm1 = AdaGN(channels, latent_dim, groups, eps)
        self.norm2 = AdaGN(channels, latent_dim, groups, eps)
        self.conv1 = SphericalConv2d(channels, channels)
        self.conv2 = SphericalConv2d(channels, channels)

    def forward(self, x: torch.Tensor, z: torch.Tensor) -> torch.Tensor:
        h = self.conv1(self.norm1(x, z), silu=True)
        h = self.conv2(self.norm2(h, z), silu=True)
        return h.add_(x)  # in place, as in ResBlock
