"""Growing a trained prior's latent: a wider network that starts out computing the same function.

A larger latent is the cheapest extra capacity a trained :class:`~roomlight.prior.model.PanoVAE` can get:
the latent enters the network only through linear maps (the encoder's ``to_moments``, the
decoder's ``from_latent`` and every AdaGN's ``to_scale_shift``), so a network with latent D' > D
can hold the trained one exactly, its first D dimensions being the old latent:

- encoder: the old mean and log-variance rows go to dimensions 0..D-1 of each half. The new
  dimensions get mean rows at a small random scale (so they carry some information about the
  input from the first step and their decoder columns receive a gradient) and log-variance rows
  of zero, i.e. posterior N(~0, 1) = the prior: they cost no KL until they are used;
- decoder: the old columns go to 0..D-1, the new columns are zero, so whatever the new
  dimensions hold the output is unchanged at the start.

Everything else (every convolution, norm and bias) is copied unchanged. Training then starts
from the old network's loss instead of from scratch (checked in ``tests/test_grow.py``).
"""

from __future__ import annotations

import torch

from roomlight.errors import RoomlightError
from roomlight.prior.model.config import ModelConfig

__all__ = ["can_grow", "grow_latent_state"]

#: Scale of the new dimensions' encoder mean rows, relative to the old rows' RMS.
NEW_MEAN_SCALE = 1e-2


def can_grow(source: ModelConfig, target: ModelConfig) -> bool:
    """True when ``target`` is ``source`` with a latent at least as large and nothing else changed."""
    if not (isinstance(source, ModelConfig) and isinstance(target, ModelConfig)) or target.latent_dim < source.latent_dim:
        return False
    return source.override(latent_dim=target.latent_dim) == target


def grow_latent_state(source_state: dict[str, torch.Tensor], source: ModelConfig, target: ModelConfig,
                      generator: torch.Generator | None = None) -> dict[str, torch.Tensor]:
    """The state dict of a ``target`` network that computes what the ``source`` network computes.

    Args:
        source_state: the trained network's state dict (``PanoVAE.state_dict()``).
        source, target: their configurations; ``target`` may differ only by a larger latent_dim.
        generator: random numbers for the new encoder mean rows (seeded by the caller).

    Returns:
        A new state dict with the target's shapes (tensors on the source's devices).
    """
    if not can_grow(source, target):
        raise RoomlightError(
            f"cannot grow a latent of {source.latent_dim} into this architecture: only latent_dim may differ, "
            f"and it may only grow (target latent_dim {target.latent_dim})")
    d, d_new = source.latent_dim, target.latent_dim
    out: dict[str, torch.Tensor] = {}
    for name, value in source_state.items():
        if name.endswith("to_moments.weight") or name.endswith("to_moments.bias"):
            out[name] = _grow_moments(value, d, d_new, generator)
        elif name.endswith("from_latent.weight") or name.endswith("to_scale_shift.weight"):
            grown = value.new_zeros(value.shape[0], d_new)
            grown[:, :d] = value
            out[name] = grown
        else:
            out[name] = value.clone()
    return out


def _grow_moments(value: torch.Tensor, d: int, d_new: int, generator: torch.Generator | None) -> torch.Tensor:
    """(2 D, ...) mean || logvar rows -> (2 D', ...): old rows in place, new means small, new logvars 0."""
    mean, logvar = value[:d], value[d:]
    extra_shape = (d_new - d, *value.shape[1:])
    new_mean = value.new_zeros(extra_shape)
    if value.dim() == 2 and d_new > d:  # weights: a small random map of the bottleneck features
        rms = float(mean.square().mean().sqrt())
        noise = torch.randn(extra_shape, generator=generator, dtype=value.dtype)
        new_mean = (noise * (NEW_MEAN_SCALE * rms)).to(value.device)
    return torch.cat([mean, new_mean, logvar, value.new_zeros(extra_shape)], dim=0)
