"""Image panels: inputs, reconstructions and prior samples side by side (training logs, ``fit-pano``)."""

from __future__ import annotations

import numpy as np
import torch

from roomlight.core.color import display_to_uint8, to_display_at_key

__all__ = ["panorama_tile", "training_panel"]


def panorama_tile(radiance: torch.Tensor, depth: torch.Tensor) -> np.ndarray:
    """One panorama as (2H, W, 3) uint8: tone-mapped radiance above log-coloured depth.

    Args:
        radiance: (3, H, W) linear; shown with the evaluation's LDR mapping (log-average
            luminance to 0.18, gamma 2.2).
        depth: (1, H, W) > 0.
    """
    from roomlight.core.io.preview import colorize_depth

    rad = display_to_uint8(to_display_at_key(radiance[None].float())[0])  # (H, W, 3)
    dep = colorize_depth(depth[0].float().numpy(), log=True)
    return np.concatenate([rad, dep], axis=0)


def training_panel(inputs: tuple[torch.Tensor, torch.Tensor], recons: tuple[torch.Tensor, torch.Tensor],
                   samples: tuple[torch.Tensor, torch.Tensor] | None = None, gap: int = 2) -> np.ndarray:
    """Grid: one column per example (input tile above its reconstruction), then sample columns.

    Args:
        inputs, recons: (radiance (B, 3, H, W), depth (B, 1, H, W)) on any device.
        samples: optional decoded prior samples, same layout.
    Returns:
        (H_panel, W_panel, 3) uint8 on white gaps.
    """
    cols = []
    for i in range(inputs[0].shape[0]):
        a = panorama_tile(inputs[0][i].cpu(), inputs[1][i].cpu())
        b = panorama_tile(recons[0][i].cpu(), recons[1][i].cpu())
        cols.append(np.concatenate([a, np.full((gap, a.shape[1], 3), 255, np.uint8), b], axis=0))
    if samples is not None:
        for i in range(samples[0].shape[0]):
            s = panorama_tile(samples[0][i].cpu(), samples[1][i].cpu())
            pad = np.full((cols[0].shape[0] - s.shape[0], s.shape[1], 3), 255, np.uint8) if cols else None
            cols.append(np.concatenate([s, pad], axis=0) if pad is not None else s)
    sep = np.full((cols[0].shape[0], gap, 3), 255, np.uint8)
    out = []
    for i, c in enumerate(cols):
        if i:
            out.append(sep)
        out.append(c)
    return np.concatenate(out, axis=1)
