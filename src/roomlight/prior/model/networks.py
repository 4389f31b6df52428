"""The networks of the prior: the panoramic encoder and decoder (paper §3.2; docs/model.md).

:class:`~roomlight.prior.model.panovae.PanoVAE` joins them into the VAE; the view encoder
(:mod:`roomlight.prior.model.view_encoder`) reuses :class:`Encoder` with one more input channel.
"""

from __future__ import annotations

import torch
from torch import nn

from roomlight.core.geometry.equirect import latitude_channels
from roomlight.prior.model.blocks import AdaGN, AdaGNResBlock, Downsample, ResBlock, SphericalConv2d, Upsample
from roomlight.prior.model.config import ModelConfig

__all__ = ["Encoder", "Decoder", "EncoderStage", "DecoderStage"]


def _with_latitude(x: torch.Tensor, enabled: bool = True) -> torch.Tensor:
    """Append (cos θ, sin θ) at pixel centres: (B, C, H, W) -> (B, C + 2, H, W); ``x`` itself
    when not ``enabled`` (the ablation without latitude channels)."""
    if not enabled:
        return x
    b, _, h, w = x.shape
    lat = latitude_channels(h, w, dtype=x.dtype, device=x.device)
    return torch.cat([x, lat.unsqueeze(0).expand(b, -1, -1, -1)], dim=1)


class EncoderStage(nn.Module):
    """Stride-2 padded conv followed by ``num_res_blocks`` ResBlocks: halves H and W."""

    def __init__(self, c_in: int, c_out: int, num_res_blocks: int, groups: int, eps: float):
        super().__init__()
        self.down = Downsample(c_in, c_out)
        self.blocks = nn.ModuleList(ResBlock(c_out, groups, eps) for _ in range(num_res_blocks))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        x = self.down(x)
        for block in self.blocks:
            x = block(x)
        return x


class DecoderStage(nn.Module):
    """Nearest x2 upsample + padded conv, then ``num_res_blocks`` AdaGN ResBlocks (plain
    ResBlocks when ``adagn`` is off)."""

    def __init__(self, c_in: int, c_out: int, num_res_blocks: int, latent_dim: int, groups: int,
                 eps: float, adagn: bool = True):
        super().__init__()
        self.adagn = adagn
        self.up = Upsample(c_in, c_out)
        self.blocks = nn.ModuleList(
            (AdaGNResBlock(c_out, latent_dim, groups, eps) if adagn else ResBlock(c_out, groups, eps))
            for _ in range(num_res_blocks)
        )

    def forward(self, x: torch.Tensor, z: torch.Tensor) -> torch.Tensor:
        x = self.up(x)
        for block in self.blocks:
            x = block(x, z) if self.adagn else block(x)
        return x


class Encoder(nn.Module):
    """x (B, in_channels, H, W) z-scored -> posterior moments (B, 2 latent_dim) = (mean ‖ logvar).

    The log-variance half is *not* clamped here; :class:`PanoVAE` clamps it.
    """

    def __init__(self, cfg: ModelConfig):
        super().__init__()
        chans = cfg.encoder_channels
        self.latitude = cfg.latitude
        self.stem = SphericalConv2d(cfg.in_channels + cfg.latitude_channels, chans[0])
        self.stages = nn.ModuleList(
            EncoderStage(chans[k], chans[k + 1], cfg.num_res_blocks, cfg.norm_groups, cfg.norm_eps)
            for k in range(cfg.num_stages)
        )
        self.out_norm = nn.GroupNorm(cfg.norm_groups, chans[-1], eps=cfg.norm_eps)
        self.out_conv = SphericalConv2d(chans[-1], cfg.z_channels)
        self.to_moments = nn.Linear(cfg.bottleneck_features, 2 * cfg.latent_dim)

    def feature_maps(self, x: torch.Tensor) -> list[torch.Tensor]:
        """Every intermediate map: [stem, stage 1, ..., stage S, bottleneck (B, z_ch, h, w)].

        All of these are equivariant to longitude rolls (by multiples of the downsampling
        factor); only the final linear layer is not.
        """
        h = self.stem(_with_latitude(x, self.latitude))
        maps = [h]
        for stage in self.stages:
            h = stage(h)
            maps.append(h)
        maps.append(self.out_conv(self.out_norm(h), silu=True))
        return maps

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        h = self.feature_maps(x)[-1]
        # Flatten in (C, H, W) order, as the authors' checkpoint expects.
        return self.to_moments(h.flatten(1))


class Decoder(nn.Module):
    """z (B, latent_dim) -> x_hat (B, in_channels, H, W) in the z-scored domain.

    z enters twice: through ``from_latent`` (Linear to the 8x16 starting map) and through every
    AdaGN, which gives all scales direct access to the global code. With ``cfg.adagn`` off the
    norms are affine GroupNorms and only ``from_latent`` sees z.
    """

    def __init__(self, cfg: ModelConfig):
        super().__init__()
        self.cfg = cfg
        chans = cfg.encoder_channels[::-1]  # e.g. [256, 256, 128, 64, 64]
        self.from_latent = nn.Linear(cfg.latent_dim, cfg.bottleneck_features)
        self.stem = SphericalConv2d(cfg.z_channels + cfg.latitude_channels, chans[0])
        self.stages = nn.ModuleList(
            DecoderStage(chans[k], chans[k + 1], cfg.num_res_blocks, cfg.latent_dim,
                         cfg.norm_groups, cfg.norm_eps, cfg.adagn)
            for k in range(cfg.num_stages)
        )
        self.out_norm = (AdaGN(chans[-1], cfg.latent_dim, cfg.norm_groups, cfg.norm_eps) if cfg.adagn
                         else nn.GroupNorm(cfg.norm_groups, chans[-1], eps=cfg.norm_eps))
        self.out_conv = SphericalConv2d(chans[-1], cfg.in_channels)

    def latent_to_map(self, z: torch.Tensor) -> torch.Tensor:
        """(B, latent_dim) -> (B, z_channels, h, w) starting map, unflattened in (C, H, W) order."""
        h, w = self.cfg.bottleneck_resolution
        return self.from_latent(z).view(z.shape[0], self.cfg.z_channels, h, w)

    def decode_map(self, h: torch.Tensor, z: torch.Tensor) -> torch.Tensor:
        """Convolutional part: starting map (B, z_ch, h, w) and z (B, D) -> (B, C, H, W).

        Equivariant to rolling ``h`` in longitude (the output rolls by the upsampling factor).
        """
        x = self.stem(_with_latitude(h, self.cfg.latitude))
        for stage in self.stages:
            x = stage(x, z)
        x = self.out_norm(x, z) if self.cfg.adagn else self.out_norm(x)
        return self.out_conv(x, silu=True)  # no output activation

    def forward(self, z: torch.Tensor) -> torch.Tensor:
        return self.decode_map(self.latent_to_map(z), z)
