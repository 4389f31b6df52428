"""Panorama reconstruction metrics of the prior evaluation (paper Tab. 1).

- LDR: radiance is tone-mapped with :func:`roomlight.core.color.to_display_at_key` (exposure so that the *target's* log-average
  luminance is 0.18, clip to [0, 1], gamma 2.2; the prediction uses the target's exposure), then
  :func:`psnr` (data range 1) and :func:`ssim`.
- HDR: :func:`psnr_hdr` on linear radiance, with the target's maximum as the peak signal.
- Light sources: :func:`peak_error_stops`, |log2| of the ratio of the brightest pixels'
  luminances: how far the strongest emitter is off, which PSNR barely sees (lights cover a few
  pixels) yet decides how a prior relights objects.
- Depth: :func:`abs_rel`, mean |D_pred - D| / D.

All functions take batches and return one value per image, (B,) float64, so callers can average
over a dataset or report per-image numbers. Pixels are weighted equally (no solid-angle weights),
as in the paper's protocol.
"""

from __future__ import annotations

import torch
import torch.nn.functional as F

from roomlight.core.color import MIDDLE_GREY, log_average_torch, luminance_torch, peak_and_median_luminance, to_display_at_key
from roomlight.errors import ShapeError

__all__ = ["LDR_KEY", "log_average_luminance", "to_ldr", "psnr", "psnr_hdr", "ssim", "abs_rel",
           "peak_error_stops", "peak_contrast", "gaussian_window"]

#: Log-average luminance the LDR mapping exposes to ("middle grey").
LDR_KEY = MIDDLE_GREY
#: The evaluation's LDR mapping under its old name (auto-exposed; compare ``roomlight.core.color.to_display``).
to_ldr = to_display_at_key
#: (B, 3, H, W) linear RGB -> (B,) log-average luminance; see :func:`roomlight.core.color.log_average_torch`.
log_average_luminance = log_average_torch


def _check(pred: torch.Tensor, target: torch.Tensor, what: str) -> None:
    if pred.shape != target.shape or pred.dim() != 4:
        raise ShapeError(f"{what}: expected two (B, C, H, W) tensors of the same shape, got "
                         f"{tuple(pred.shape)} and {tuple(target.shape)}")


def psnr(pred: torch.Tensor, target: torch.Tensor, data_range: float = 1.0) -> torch.Tensor:
    """(B,) 10 log10(data_range^2 / MSE) per image (inf for identical images)."""
    _check(pred, target, "psnr")
    mse = (pred.double() - target.double()).pow(2).flatten(1).mean(1)
    return 10.0 * torch.log10(data_range**2 / mse)


def psnr_hdr(pred: torch.Tensor, target: torch.Tensor) -> torch.Tensor:
    """(B,) PSNR of linear radiance with the target's maximum as the peak: 10 log10(max(T)^2 / MSE)."""
    _check(pred, target, "psnr_hdr")
    peak = target.double().flatten(1).amax(1)
    mse = (pred.double() - target.double()).pow(2).flatten(1).mean(1)
    return 10.0 * torch.log10(peak**2 / mse)


def gaussian_window(size: int = 11, sigma: float = 1.5, dtype=torch.float64) -> torch.Tensor:
    """(size,) normalised 1-D Gaussian; the 2-D SSIM window is its outer product."""
    x = torch.arange(size, dtype=dtype) - (size - 1) / 2.0
    g = torch.exp(-(x**2) / (2.0 * sigma**2))
    return g / g.sum()


def ssim(pred: torch.Tensor, target: torch.Tensor, data_range: float = 1.0, window: int = 11,
         sigma: float = 1.5, k1: float = 0.01, k2: float = 0.03) -> torch.Tensor:
    """(B,) structural similarity (Wang et al. 2004) per image, averaged over channels.

    Local statistics use an 11 x 11 Gaussian window (sigma 1.5), evaluated only where the window
    fits inside the image ("valid"), with population (biased) variances:

        SSIM = (2 mu_x mu_y + C1)(2 s_xy + C2) / ((mu_x^2 + mu_y^2 + C1)(s_x^2 + s_y^2 + C2)),
        C1 = (k1 L)^2, C2 = (k2 L)^2, L = data_range.

    Computed in float64 with separable convolutions.
    """
    _check(pred, target, "ssim")
    b, c, h, w = pred.shape
    if h < window or w < window:
        raise ShapeError(f"ssim: images of {h}x{w} are smaller than the {window}x{window} window")
    g = gaussian_window(window, sigma).to(pred.device)
    gx = g.view(1, 1, 1, window).repeat(c, 1, 1, 1)
    gy = g.view(1, 1, window, 1).repeat(c, 1, 1, 1)

    def blur(t):
        return F.conv2d(F.conv2d(t, gx, groups=c), gy, groups=c)

    x, y = pred.double(), target.double()
    mx, my = blur(x), blur(y)
    sxx = blur(x * x) - mx * mx
    syy = blur(y * y) - my * my
    sxy = blur(x * y) - mx * my
    c1, c2 = (k1 * data_range) ** 2, (k2 * data_range) ** 2
    s = ((2 * mx * my + c1) * (2 * sxy + c2)) / ((mx * mx + my * my + c1) * (sxx + syy + c2))
    return s.flatten(1).mean(1)


def peak_error_stops(pred: torch.Tensor, target: torch.Tensor, floor: float = 1e-12) -> torch.Tensor:
    """(B,) |log2(max luminance of pred / max luminance of target)| per image, in stops.

    pred, target: (B, 3, H, W) linear radiance on the same exposure scale. 0 when the brightest
    pixels are equally bright; 3 when one is 8x the other. Luminances below ``floor`` count as it.
    """
    _check(pred, target, "peak_error_stops")
    peak_p = luminance_torch(pred.double()).flatten(1).amax(1).clamp_min(floor)
    peak_t = luminance_torch(target.double()).flatten(1).amax(1).clamp_min(floor)
    return torch.log2(peak_p / peak_t).abs()


def peak_contrast(radiance: torch.Tensor) -> torch.Tensor:
    """(B,) brightest pixel's luminance over the median luminance, per (B, 3, H, W) panorama.

    The median is floored at 1e-12 (a black panorama gives a huge ratio, not a division by zero).
    Needs no reference, so it also describes samples: six procedural 64 x 128 rooms measured
    26-162x; a prior whose decoded rooms sit near 2x shows no light sources.
    """
    peak, median = peak_and_median_luminance(radiance)
    return peak / median.clamp_min(1e-12)


def abs_rel(pred: torch.Tensor, target: torch.Tensor) -> torch.Tensor:
    """(B,) mean relative depth error |D_pred - D| / D per image (target depth > 0)."""
    _check(pred, target, "abs_rel")
    t = target.double()
    return ((pred.double() - t).abs() / t).flatten(1).mean(1)

