"""Multi-scale Scharr gradient loss (paper eq. 4).

L_grad = 1/(2S) * sum_{o=1..S} sum_{d in {u, v}} mean_o |grad_d pred^(o) - grad_d target^(o)|

where octave 1 is the full-resolution map, each further octave is a 2x2 average pooling of the
previous one, and mean_o averages over batch, channels and pixels of octave o. The Scharr
kernels are divided by 32 (the sum of their absolute weights), which makes them unbiased
derivative estimators: a ramp x(i, j) = j has grad_u = (3 + 10 + 3) * 2 / 32 = 1 per pixel.
Borders use spherical padding, so there is no seam at u = 0 or artefact at the poles.
"""

from __future__ import annotations

import torch
import torch.nn.functional as F

from roomlight.errors import ShapeError
from roomlight.core.geometry.padding import spherical_pad
from roomlight.prior.losses.l1 import check_same_shape

__all__ = ["SCHARR_U", "SCHARR_V", "scharr_gradients", "gradient_loss"]

#: Horizontal (u, along columns) Scharr kernel / 32, applied as a cross-correlation:
#: grad_u(i, j) = sum_{a,b} K[a, b] x(i + a - 1, j + b - 1), positive where x grows with j.
SCHARR_U = torch.tensor([[-3.0, 0.0, 3.0], [-10.0, 0.0, 10.0], [-3.0, 0.0, 3.0]]) / 32.0
#: Vertical (v, along rows) Scharr kernel / 32; positive where x grows with the row index.
SCHARR_V = SCHARR_U.t().contiguous()


def scharr_gradients(x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """Per-channel normalised Scharr derivatives with spherical padding.

    Args:
        x: (B, C, H, W) equirectangular maps, W even.
    Returns:
        (grad_u, grad_v), each (B, C, H, W).
    """
    if x.dim() != 4:
        raise ShapeError(f"scharr_gradients: expected (B, C, H, W), got {tuple(x.shape)}")
    c = x.shape[1]
    kernels = torch.stack([SCHARR_U, SCHARR_V]).to(dtype=x.dtype, device=x.device)  # (2, 3, 3)
    weight = kernels.repeat(c, 1, 1).unsqueeze(1)  # (2C, 1, 3, 3): u, v for each channel
    g = F.conv2d(spherical_pad(x, 1), weight, groups=c)  # (B, 2C, H, W), channel-interleaved
    g = g.view(x.shape[0], c, 2, *x.shape[-2:])
    return g[:, :, 0], g[:, :, 1]


def gradient_loss(pred: torch.Tensor, target: torch.Tensor, levels: int = 4) -> torch.Tensor:
    """Scharr gradient loss over a ``levels``-octave average-pooling pyramid (paper eq. 4).

    Args:
        pred, target: (B, C, H, W) maps in the z-scored domain (radiance C = 3 or depth C = 1).
            H must be divisible by 2 ** (levels - 1) so every octave keeps an even width.
        levels: number of octaves S (4 in the paper).
    Returns:
        scalar tensor.
    """
    check_same_shape(pred, target, "gradient_loss")
    if levels < 1:
        raise ShapeError(f"gradient_loss: levels must be >= 1, got {levels}")
    h = pred.shape[-2] if pred.dim() == 4 else 0
    if pred.dim() != 4 or h % (2 ** (levels - 1)) or pred.shape[-1] != 2 * h:
        raise ShapeError(
            f"gradient_loss: expected (B, C, H, 2H) with H divisible by 2^(levels-1) = "
            f"{2 ** (levels - 1)}, got {tuple(pred.shape)} (use fewer levels or resample)"
        )
    # Scharr filtering, padding and average pooling are all linear, so the difference of the
    # gradients equals the gradient of the difference: filter the residual once.
    r = pred - target
    total = r.new_zeros(())
    for o in range(levels):
        if o > 0:
            r = F.avg_pool2d(r, 2)
        gu, gv = scharr_gradients(r)
        total = total + gu.abs().mean() + gv.abs().mean()
    return total / (2 * levels)
