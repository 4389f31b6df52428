"""Named conversions between torch image layouts and Mitsuba tensors (DESIGN.md §1).

Torch images are (B, C, H, W) or (C, H, W); Mitsuba ``TensorXf`` textures and films are
(H, W, C). Every crossing goes through these helpers so the layout is never guessed ad hoc.
"""

from __future__ import annotations

import numpy as np
import torch

__all__ = ["chw_to_hwc", "hwc_to_chw", "to_mitsuba_tensor", "from_mitsuba_tensor"]


def chw_to_hwc(x: torch.Tensor) -> torch.Tensor:
    """(C, H, W) or (1, C, H, W) -> (H, W, C), contiguous."""
    if x.dim() == 4:
        if x.shape[0] != 1:
            raise ValueError(f"chw_to_hwc: batch of {x.shape[0]} images; convert one at a time")
        x = x[0]
    return x.permute(1, 2, 0).contiguous()


def hwc_to_chw(x: torch.Tensor, batch: bool = False) -> torch.Tensor:
    """(H, W, C) -> (C, H, W), or (1, C, H, W) with ``batch=True``."""
    y = x.permute(2, 0, 1).contiguous()
    return y.unsqueeze(0) if batch else y


def to_mitsuba_tensor(x):
    """torch tensor / numpy array (H, W, C) -> ``mi.TensorXf`` (float32, no autograd)."""
    import mitsuba as mi

    if isinstance(x, torch.Tensor):
        x = x.detach().to("cpu", torch.float32).numpy()
    return mi.TensorXf(np.ascontiguousarray(x, dtype=np.float32))


def from_mitsuba_tensor(x) -> torch.Tensor:
    """``mi.TensorXf`` / Bitmap (H, W, C) -> float32 torch tensor on the CPU."""
    return torch.from_numpy(np.array(x, dtype=np.float32, copy=True))
