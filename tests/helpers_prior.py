"""A tiny untrained prior for tests that need a PanoVAE's shapes, not its knowledge."""

from __future__ import annotations

import torch


def tiny_prior():
    """The ``tiny`` preset, seeded (torch.manual_seed(0)), with fixed normalisation statistics."""
    from roomlight.prior.model import ModelConfig, Normalization, PanoVAE

    torch.manual_seed(0)
    norm = Normalization(mean=torch.tensor([0.5, 0.5, 0.5, 1.0]), std=torch.tensor([0.5, 0.5, 0.5, 0.3]))
    return PanoVAE(ModelConfig.preset("tiny"), normalization=norm)
