"""Input normalisation of the prior (paper §3.3): log transforms + per-channel z-scoring.

The network sees x = (log1p(R), log1p(G), log1p(B), log(D)) standardised per channel with
dataset statistics. Radiance gets log(1 + L) so that highlights are compressed without spending
precision on near-black values; depth never vanishes, so plain log(D) keeps uniform relative
precision. The statistics are computed from the training data (:meth:`Normalization.from_data`)
and stored in every checkpoint; nothing here is hard-coded (the authors' constants live with
their loader in :mod:`roomlight.prior.model.convert`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Iterable

import torch

from roomlight.errors import RoomlightError, ShapeError

__all__ = ["Normalization", "RADIANCE_MAX", "CHANNELS"]

#: Decoded radiance is clamped to [0, RADIANCE_MAX] (the authors' bound), so that an untrained or
#: extrapolating decoder cannot produce inf through expm1.
RADIANCE_MAX = 1e6

#: Names of the four normalised channels, in order.
CHANNELS = ("log1p_R", "log1p_G", "log1p_B", "log_depth")


def _as_batch(t: torch.Tensor, channels: int, what: str) -> torch.Tensor:
    """Accept (C, H, W), (B, C, H, W), or for one channel also (H, W); return (B, C, H, W)."""
    if channels == 1 and t.dim() == 2:
        t = t[None, None]
    elif t.dim() == 3:
        t = t[None]
    if t.dim() != 4 or t.shape[1] != channels:
        raise ShapeError(
            f"{what}: expected shape (B, {channels}, H, W) or ({channels}, H, W) "
            f"(channels first), got {tuple(t.shape)}"
        )
    return t


@dataclass(frozen=True)
class Normalization:
    """Per-channel statistics of (log1p R, log1p G, log1p B, log depth)."""

    #: Mean of each of the four transformed channels.
    mean: tuple[float, float, float, float]
    #: Standard deviation (population) of each transformed channel; must be positive.
    std: tuple[float, float, float, float]

    def __post_init__(self) -> None:
        object.__setattr__(self, "mean", tuple(float(v) for v in self.mean))
        object.__setattr__(self, "std", tuple(float(v) for v in self.std))
        if len(self.mean) != 4 or len(self.std) != 4:
            raise RoomlightError(
                f"Normalization: expected 4 means and 4 stds (R, G, B, depth), "
                f"got {len(self.mean)} and {len(self.std)}"
            )
        if not all(math.isfinite(v) for v in self.mean + self.std) or min(self.std) <= 0:
            raise RoomlightError(
                f"Normalization: statistics must be finite with std > 0, got mean={self.mean}, "
                f"std={self.std} (recompute them with Normalization.from_data on valid data)"
            )

    # ------------------------------------------------------------------ transforms
    def _stats(self, like: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        mean = torch.tensor(self.mean, dtype=like.dtype, device=like.device).view(1, 4, 1, 1)
        std = torch.tensor(self.std, dtype=like.dtype, device=like.device).view(1, 4, 1, 1)
        return mean, std

    def normalize(self, radiance: torch.Tensor, depth: torch.Tensor) -> torch.Tensor:
        """Map linear radiance and depth to the network's input.

        Args:
            radiance: (B, 3, H, W) linear RGB, >= 0 (small negatives from resampling are clamped).
            depth: (B, 1, H, W) radial depth, > 0, in the units the statistics were computed in
                (metres for roomlight datasets).
        Returns:
            (B, 4, H, W) z-scored (log1p R, log1p G, log1p B, log depth).
        """
        radiance = _as_batch(radiance, 3, "normalize: radiance")
        depth = _as_batch(depth, 1, "normalize: depth")
        if radiance.shape[0] != depth.shape[0] or radiance.shape[-2:] != depth.shape[-2:]:
            raise ShapeError(
                f"normalize: radiance {tuple(radiance.shape)} and depth {tuple(depth.shape)} "
                "must have the same batch size and H x W"
            )
        if bool((depth <= 0).any()) or not bool(torch.isfinite(depth).all()):
            raise RoomlightError(
                "normalize: depth must be finite and > 0 everywhere (log depth is undefined "
                "otherwise); fill holes, e.g. with the nearest valid depth, before encoding"
            )
        x = torch.cat([torch.log1p(radiance.clamp_min(0.0)), torch.log(depth)], dim=1)
        mean, std = self._stats(x)
        return (x - mean) / std

    def denormalize(self, x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """Inverse of :meth:`normalize` for network outputs.

        Args:
            x: (B, 4, H, W) z-scored channels (e.g. the decoder output).
        Returns:
            radiance (B, 3, H, W) linear, clamped to [0, 1e6]; depth (B, 1, H, W) = exp(.) > 0.
        """
        if x.dim() != 4 or x.shape[1] != 4:
            raise ShapeError(f"denormalize: expected (B, 4, H, W), got {tuple(x.shape)}")
        mean, std = self._stats(x)
        y = x * std + mean
        radiance = torch.expm1(y[:, :3]).clamp(0.0, RADIANCE_MAX)
        depth = torch.exp(y[:, 3:])
        return radiance, depth

    # ------------------------------------------------------------------ statistics
    @classmethod
    def from_data(cls, pairs: Iterable[tuple[torch.Tensor, torch.Tensor]]) -> "Normalization":
        """Compute the statistics by streaming over (radiance, depth) pairs.

        Each item is radiance (3, H, W) or (B, 3, H, W) and depth (1, H, W), (H, W) or
        (B, 1, H, W); sizes may vary between items. Every pixel counts once (no solid-angle
        weighting, matching the per-pixel losses). Batches are merged with Chan et al.'s
        parallel update in float64, so the result does not depend on the batching and does not
        suffer from the cancellation of a naive sum of squares.
        """
        count = 0
        mean = torch.zeros(4, dtype=torch.float64)
        m2 = torch.zeros(4, dtype=torch.float64)
        for radiance, depth in pairs:
            radiance = _as_batch(torch.as_tensor(radiance), 3, "Normalization.from_data: radiance")
            depth = _as_batch(torch.as_tensor(depth), 1, "Normalization.from_data: depth")
            if bool((depth <= 0).any()):
                raise RoomlightError(
                    "Normalization.from_data: depth must be > 0 everywhere; fill holes first"
                )
            x = torch.cat(
                [torch.log1p(radiance.double().clamp_min(0.0)), torch.log(depth.double())], dim=1
            )
            x = x.transpose(0, 1).reshape(4, -1)  # (4, N)
            n = x.shape[1]
            if n == 0:
                continue
            b_mean = x.mean(dim=1)
            b_m2 = ((x - b_mean[:, None]) ** 2).sum(dim=1)
            delta = b_mean - mean
            total = count + n
            mean = mean + delta * (n / total)
            m2 = m2 + b_m2 + delta**2 * (count * n / total)
            count = total
        if count == 0:
            raise RoomlightError("Normalization.from_data: no data (the iterable was empty)")
        std = torch.sqrt(m2 / count)
        return cls(mean=tuple(mean.tolist()), std=tuple(std.tolist()))

    # ------------------------------------------------------------------ (de)serialisation
    def to_dict(self) -> dict:
        """JSON-friendly dict, with the channel names for readers of ``config.json``."""
        return {"channels": list(CHANNELS), "mean": list(self.mean), "std": list(self.std)}

    @classmethod
    def from_dict(cls, d: dict) -> "Normalization":
        """Inverse of :meth:`to_dict`."""
        try:
            return cls(mean=tuple(d["mean"]), std=tuple(d["std"]))
        except KeyError as e:
            raise RoomlightError(
                f"Normalization: missing key {e.args[0]!r}; expected a dict with 'mean' and 'std'"
            ) from None
