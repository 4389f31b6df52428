"""Layers equivariant to rotations about the vertical axis (the building blocks of VENI).

Features are sets of channels, each channel a small vector whose first two coordinates are the
**planar** part (the world x and z components, which a rotation about y turns) and whose other
coordinates are **invariant** (the y component, colours, depth: untouched by such a rotation):

    x: (..., C, 2 + c)     x[..., :2] planar, x[..., 2:] invariant

A rotation by angle δ about the up axis acts on the planar part as the complex product
(p_x + i p_z) · e^{iδ}, i.e. ``rotate_planar`` below; see docs/model.md ("VENI") for why rolling
a panorama by k columns is exactly that rotation with δ = 2πk/W.

Two families of layers, as in VENI (Walker et al., CVPR 2026):

- :class:`SO2Linear`: the projection that mixes planar and invariant parts. Its planar output is a
  combination of the input channels' planar vectors with coefficients affine in the same channel's
  invariants; its invariant output is a dense layer over the invariants and the planar norms.
- :class:`VNLinear`, :class:`VNReLU`, :class:`VNLayerNorm`, :class:`VNAttention` (Vector Neurons):
  every channel is one vector of all 2 + c coordinates; they mix channels only, never coordinates,
  so they commute with any orthogonal map of the coordinates, the planar rotation included.

Shapes use ``...`` for any leading batch / token dimensions.
"""

from __future__ import annotations

import math

import torch
from torch import nn

__all__ = ["rotate_planar", "SO2Linear", "VNLinear", "VNReLU", "VNLayerNorm", "VNAttention", "VNBlock"]

#: Added under square roots and divisions by vector norms (their gradient is infinite at 0).
NORM_EPS = 1e-6


def rotate_planar(x: torch.Tensor, angle: float) -> torch.Tensor:
    """Rotate the planar part x[..., :2] by ``angle`` radians (p -> p e^{i angle}); the rest is kept."""
    c, s = math.cos(angle), math.sin(angle)
    px, pz = x[..., 0], x[..., 1]
    return torch.cat([torch.stack([px * c - pz * s, px * s + pz * c], -1), x[..., 2:]], -1)


def _norm(v: torch.Tensor, dim: int = -1, keepdim: bool = False) -> torch.Tensor:
    return torch.sqrt(v.square().sum(dim, keepdim=keepdim) + NORM_EPS)


class SO2Linear(nn.Module):
    """(..., C_in, 2 + c_in) -> (..., C_out, 2 + c_out), equivariant to planar rotations.

    With P (..., C_in, 2) the planar part, Q (..., C_in, c_in) the invariant part and
    T = [1, Q] (..., C_in, 1 + c_in):

        planar out[o]    = sum_i sum_k A[o, k, i] T[i, k] P[i]                 (no bias: a bias would not turn)
        invariant out    = B · vec([Q, |P|]) + b   reshaped to (C_out, c_out)

    Rotating P leaves T and |P| unchanged and turns every planar output by the same angle.
    """

    def __init__(self, c_in: int, inv_in: int, c_out: int, inv_out: int):
        super().__init__()
        self.c_in, self.inv_in, self.c_out, self.inv_out = c_in, inv_in, c_out, inv_out
        bound = math.sqrt(1.0 / (c_in * (1 + inv_in) + c_out))
        self.planar = nn.Parameter(torch.empty(c_out, 1 + inv_in, c_in).uniform_(-bound, bound))
        self.invariant = nn.Linear(c_in * (1 + inv_in), c_out * inv_out) if inv_out > 0 else None

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        if x.shape[-2:] != (self.c_in, 2 + self.inv_in):
            raise ValueError(f"SO2Linear: expected (..., {self.c_in}, {2 + self.inv_in}), got {tuple(x.shape)}")
        p, q = x[..., :2], x[..., 2:]
        t = torch.cat([torch.ones_like(q[..., :1]), q], -1)                       # (..., C_in, 1 + c_in)
        # (T[i, k] P[i]) flattened over (i, k), then one matrix product: the three-operand einsum
        # would materialise a (..., C_out, 1 + c_in, C_in, 2) intermediate.
        tp = (t[..., :, :, None] * p[..., :, None, :]).flatten(-3, -2)             # (..., C_in (1 + c_in), 2)
        weight = self.planar.permute(0, 2, 1).reshape(self.c_out, -1)               # (C_out, C_in (1 + c_in))
        planar = torch.matmul(weight, tp)                                          # (..., C_out, 2)
        if self.invariant is None:
            return planar
        feats = torch.cat([q, _norm(p, keepdim=True)], -1).flatten(-2)             # (..., C_in (c_in + 1))
        inv = self.invariant(feats).unflatten(-1, (self.c_out, self.inv_out))     # (..., C_out, c_out)
        return torch.cat([planar, inv], -1)


class VNLinear(nn.Module):
    """(..., C_in, d) -> (..., C_out, d): y_o = sum_i W[o, i] x_i (channels mixed, coordinates not)."""

    def __init__(self, c_in: int, c_out: int):
        super().__init__()
        self.weight = nn.Parameter(torch.empty(c_out, c_in).uniform_(-1, 1) / math.sqrt(c_in))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return torch.matmul(self.weight, x)


class VNReLU(nn.Module):
    """Vector-neuron ReLU (Deng et al. 2021): q = W x, k = U x per channel; where q points away from the
    learned direction k (q·k < 0) its component along k is removed, else q passes unchanged.

        out = q - [q·k < 0] (q·k̂) k̂
    """

    def __init__(self, channels: int):
        super().__init__()
        self.q = VNLinear(channels, channels)
        self.k = VNLinear(channels, channels)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        q, k = self.q(x), self.k(x)
        k_hat = k / _norm(k, keepdim=True)
        dot = (q * k_hat).sum(-1, keepdim=True)
        return q - torch.where(dot < 0, dot, torch.zeros_like(dot)) * k_hat


class VNLayerNorm(nn.Module):
    """Layer norm of the channels' lengths: x_c <- x_c / |x_c| * LN(|x|)_c (direction kept)."""

    def __init__(self, channels: int):
        super().__init__()
        self.norm = nn.LayerNorm(channels)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        r = _norm(x)                                                               # (..., C)
        return x / r[..., None] * self.norm(r)[..., None]


class VNAttention(nn.Module):
    """Multi-head self-attention over tokens whose features are (C, d) vector channels.

    x (B, T, C, d) -> (B, T, C, d). The logits are inner products over (channel, coordinate),
    which every orthogonal map of the coordinates keeps; there is no positional encoding, so a
    permutation of the tokens permutes the output the same way.
    """

    def __init__(self, channels: int, heads: int):
        super().__init__()
        if channels % heads:
            raise ValueError(f"VNAttention: {heads} heads do not divide {channels} channels")
        self.heads = heads
        self.qkv = VNLinear(channels, 3 * channels)
        self.out = VNLinear(channels, channels)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        b, t, c, d = x.shape
        q, k, v = self.qkv(x).chunk(3, dim=2)                                     # (B, T, C, d) each
        split = lambda y: y.reshape(b, t, self.heads, (c // self.heads) * d).transpose(1, 2)  # noqa: E731
        o = torch.nn.functional.scaled_dot_product_attention(split(q), split(k), split(v))  # (B, h, T, C/h d)
        return self.out(o.transpose(1, 2).reshape(b, t, c, d))


class VNBlock(nn.Module):
    """Pre-norm transformer block of vector neurons: x + Attn(LN x), then x + FF(LN x), where
    FF = VNLinear(C -> mC) -> VNReLU -> VNLinear(mC -> C)."""

    def __init__(self, channels: int, heads: int, ff_mult: int = 2):
        super().__init__()
        self.norm1, self.norm2 = VNLayerNorm(channels), VNLayerNorm(channels)
        self.attn = VNAttention(channels, heads)
        self.ff = nn.Sequential(VNLinear(channels, ff_mult * channels), VNReLU(ff_mult * channels),
                                VNLinear(ff_mult * channels, channels))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        x = x + self.attn(self.norm1(x))
        return x + self.ff(self.norm2(x))
