"""Conversions between torch / numpy images and Mitsuba tensors (docs/conventions.md).

Mitsuba ``TensorXf`` textures and films are (H, W, C), as are the torch images handed to and
returned by the renderer (torch's own (B, C, H, W) layout stays inside the model code).
"""

from __future__ import annotations

import numpy as np
import torch

__all__ = ["to_mitsuba_tensor", "from_mitsuba_tensor"]


def to_mitsuba_tensor(x):
    """torch tensor / numpy array (H, W, C) -> ``mi.TensorXf`` (float32, no autograd)."""
    import mitsuba as mi

    if isinstance(x, torch.Tensor):
        x = x.detach().to("cpu", torch.float32).numpy()
    return mi.TensorXf(np.ascontiguousarray(x, dtype=np.float32))


def from_mitsuba_tensor(x) -> torch.Tensor:
    """``mi.TensorXf`` / Bitmap (H, W, C) -> float32 torch tensor on the CPU."""
    return torch.from_numpy(np.array(x, dtype=np.float32, copy=True))
