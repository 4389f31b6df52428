"""Figures of prior samples (paper Fig. 3) and latent interpolations."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import torch

from roomlight.core.color import display_to_uint8, to_display_at_key

__all__ = ["samples_figure", "interpolation_strip"]


def _ldr_uint8(radiance_chw: torch.Tensor, reference_chw: torch.Tensor | None = None) -> np.ndarray:
    ref = None if reference_chw is None else reference_chw[None].float()
    return display_to_uint8(to_display_at_key(radiance_chw[None].float(), reference=ref)[0])


def samples_figure(path: str | Path, radiance: torch.Tensor, depth: torch.Tensor,
                   renders: list[torch.Tensor] | None = None, title: str = "samples of the prior") -> Path:
    """One row per sample: tone-mapped radiance | log-coloured depth | probes lit by it.

    Args:
        radiance: (N, 3, H, W) linear; depth: (N, 1, H, W).
        renders: optional list of N (h, w, 3) linear probe renders, exposed like their panorama.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from roomlight.core.io.preview import colorize_depth

    n = radiance.shape[0]
    ncol = 3 if renders else 2
    ratios = [2, 2, 1] if renders else [2, 2]
    row = 1.45  # inches per sample row; a 2:1 panorama is then ~2.6 inches wide
    fig, axes = plt.subplots(n, ncol, figsize=(0.62 * row * 2 * sum(ratios) / 2 + 0.6, row * n + 0.5), squeeze=False,
                             gridspec_kw={"width_ratios": ratios})
    for i in range(n):
        axes[i, 0].imshow(_ldr_uint8(radiance[i]))
        axes[i, 1].imshow(colorize_depth(depth[i, 0].numpy(), log=True))
        dmin, dmax = float(depth[i].min()), float(depth[i].max())
        axes[i, 1].set_title(f"depth {dmin:.2g}–{dmax:.2g}", fontsize=7, pad=2)
        if renders:
            axes[i, 2].imshow(_ldr_uint8(renders[i].permute(2, 0, 1), radiance[i]))
        for ax in axes[i]:
            ax.set_xticks([])
            ax.set_yticks([])
    axes[0, 0].set_title("radiance (tone-mapped)", fontsize=8)
    if renders:
        axes[0, 2].set_title("glossy probes lit by it", fontsize=8)
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return Path(path)


def interpolation_strip(path: str | Path, radiance: torch.Tensor, depth: torch.Tensor, gap: int = 2) -> Path:
    """Columns = interpolation steps; top row radiance, bottom row depth (PNG, native resolution)."""
    from roomlight.core.io import save_png
    from roomlight.core.io.preview import colorize_depth

    dmin, dmax = float(depth.min()), float(depth.max())
    cols = []
    for i in range(radiance.shape[0]):
        r = _ldr_uint8(radiance[i], radiance[0])
        d = colorize_depth(depth[i, 0].numpy(), vmin=dmin, vmax=dmax, log=True)
        cols.append(np.concatenate([r, np.full((gap, r.shape[1], 3), 255, np.uint8), d], axis=0))
        cols.append(np.full((cols[-1].shape[0], gap, 3), 255, np.uint8))
    save_png(path, np.concatenate(cols[:-1], axis=1))
    return Path(path)
