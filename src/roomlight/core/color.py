"""Colour: the one place for luminance, exposure keys, the display gamma and display mapping.

Everything in roomlight is linear Rec.709 RGB (sRGB primaries) in the panorama's units; this
module holds the few photometric conventions that the rest of the package shares, so that the
training losses, the exposure calibration of panoramas, the metrics, the benchmark camera and
the previews all agree on them (docs/conventions.md, "Radiance and exposure"):

- :data:`REC709_LUMA`     Rec.709 luminance weights, Y = 0.2126 R + 0.7152 G + 0.0722 B;
- :data:`LOG_EPS`         added to Y before every log (black pixels stay finite), 1e-6;
- :data:`MIDDLE_GREY`     the photographic key an auto-exposure maps the log-average to, 0.18;
- :data:`DISPLAY_GAMMA`   the gamma of every 8-bit image roomlight writes or reads, 2.2.

Functions come in a numpy flavour (channel-last, ``(..., 3)``) and a torch flavour
(channel-first, ``(..., 3, H, W)``), following the layout conventions of each library. This
module imports neither torch nor any other roomlight module, so every layer may use it.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "REC709_LUMA", "LOG_EPS", "MIDDLE_GREY", "DISPLAY_GAMMA",
    "luminance_np", "luminance_torch", "peak_and_median_luminance", "log_average_np", "log_average_torch",
    "to_display", "to_display_torch", "to_display_at_key", "display_to_uint8", "display_to_linear",
    "srgb_to_linear", "linear_to_srgb",
]

#: Rec.709 / sRGB luminance weights of linear RGB.
REC709_LUMA = (0.2126, 0.7152, 0.0722)
#: Added to the luminance before taking its log (exposure calibration, metering, log-averages).
LOG_EPS = 1e-6
#: Photographic middle grey: the log-average luminance an auto-exposure maps to.
MIDDLE_GREY = 0.18
#: Display gamma of 8-bit images (previews, the benchmark's recordings, the LDR metrics).
DISPLAY_GAMMA = 2.2


def luminance_np(rgb) -> np.ndarray:
    """Rec.709 luminance of channel-last linear RGB.

    Args:
        rgb: array-like (..., 3), linear.
    Returns:
        (...) float array (float64 unless the input is a float array of another precision).
    """
    a = np.asarray(rgb)
    if a.shape[-1:] != (3,):
        raise ValueError(f"luminance: expected (..., 3) linear RGB, got shape {a.shape}")
    wr, wg, wb = REC709_LUMA
    return wr * a[..., 0] + wg * a[..., 1] + wb * a[..., 2]


def luminance_torch(rgb, keepdim: bool = False):
    """Rec.709 luminance of channel-first linear RGB.

    Args:
        rgb: torch tensor (..., 3, H, W), linear.
        keepdim: keep the channel axis, (..., 1, H, W).
    Returns:
        (..., H, W) tensor (or (..., 1, H, W)), same dtype and device as the input.
    """
    if rgb.dim() < 3 or rgb.shape[-3] != 3:
        raise ValueError(f"luminance: expected (..., 3, H, W) linear RGB, got {tuple(rgb.shape)}")
    wr, wg, wb = REC709_LUMA
    y = wr * rgb[..., 0, :, :] + wg * rgb[..., 1, :, :] + wb * rgb[..., 2, :, :]
    return y.unsqueeze(-3) if keepdim else y


def peak_and_median_luminance(rgb) -> tuple:
    """(B,), (B,) brightest and median Rec.709 luminance (float64) of (B, 3, H, W) linear RGB.

    The median of an even count is the lower of the two middle values (torch's rule).
    """
    lum = luminance_torch(rgb.double()).flatten(1)
    return lum.amax(1), lum.median(1).values


def log_average_np(rgb, mask=None) -> float:
    """Log-average luminance ``exp(mean(log(Y + LOG_EPS)))`` of channel-last RGB, in float64.

    Args:
        rgb: (..., 3) linear RGB; negative values count as 0.
        mask: optional bool array over the leading axes; only those pixels are averaged.
    Returns:
        a float > 0 (NaN if the input holds NaN).
    """
    y = luminance_np(np.clip(np.asarray(rgb, dtype=np.float64), 0.0, None))
    if mask is not None:
        y = y[np.asarray(mask, bool)]
    return float(np.exp(np.mean(np.log(y + LOG_EPS))))


def log_average_torch(rgb):
    """Per-image log-average luminance of a batch.

    Args:
        rgb: (B, 3, H, W) linear RGB; negative values count as 0.
    Returns:
        (B,) ``exp(mean(log(Y + LOG_EPS)))``, the input's dtype.
    """
    y = luminance_torch(rgb.clamp_min(0.0)).flatten(1)
    return (y + LOG_EPS).log().mean(1).exp()


def to_display(radiance, gamma: float = DISPLAY_GAMMA) -> np.ndarray:
    """Display values of linear radiance that is *already exposed*: ``clip(x, 0, 1) ** (1 / gamma)``.

    No exposure is applied (compare :func:`to_display_at_key`). NaN shows as 0, +inf as 1.

    Args:
        radiance: array-like (or torch tensor) of any shape, linear.
    Returns:
        float64 array of the same shape, in [0, 1].
    """
    if hasattr(radiance, "detach"):
        radiance = radiance.detach().cpu().numpy()
    x = np.nan_to_num(np.asarray(radiance, dtype=np.float64), nan=0.0, posinf=1.0, neginf=0.0)
    return np.clip(x, 0.0, 1.0) ** (1.0 / gamma)


def to_display_torch(radiance, gamma: float = DISPLAY_GAMMA):
    """Torch version of :func:`to_display`: ``clamp(x, 0, 1) ** (1 / gamma)``, same shape and dtype."""
    return radiance.clamp(0.0, 1.0).pow(1.0 / gamma)


def to_display_at_key(radiance, reference=None, key: float = MIDDLE_GREY, gamma: float = DISPLAY_GAMMA):
    """Auto-exposed display values of a batch: the exposure puts ``reference``'s log-average at ``key``.

    ``s = key / log_average_torch(reference)`` per image, then ``clamp(x * s, 0, 1) ** (1 / gamma)``.
    ``reference`` defaults to ``radiance`` itself; pass the target when mapping a prediction, so
    that both share one exposure and an exposure error shows in a metric.

    Args:
        radiance: (B, 3, H, W) linear torch tensor; reference: the same shape, or None.
    Returns:
        (B, 3, H, W) in [0, 1], the input's dtype (computed in float64).
    """
    ref = radiance if reference is None else reference
    s = key / log_average_torch(ref.double())
    x = radiance.double() * s.view(-1, 1, 1, 1).to(radiance.device)
    return to_display_torch(x, gamma).to(radiance.dtype)


def display_to_uint8(display) -> np.ndarray:
    """Display values in [0, 1] (numpy, or a torch tensor (3, H, W)) -> uint8 ``round(255 x)``.

    A torch tensor is taken as channel-first and returned channel-last, (H, W, 3).
    """
    if hasattr(display, "detach"):
        display = display.detach().cpu()
        display = (display.permute(1, 2, 0) if display.dim() == 3 else display).numpy()
    return np.rint(np.clip(np.asarray(display, dtype=np.float64), 0.0, 1.0) * 255.0).astype(np.uint8)


def display_to_linear(display, gamma: float = DISPLAY_GAMMA):
    """Inverse of the display gamma: ``x ** gamma`` for display values in [0, 1] (numpy or torch)."""
    return display ** gamma


def srgb_to_linear(encoded):
    """The sRGB transfer function undone (IEC 61966-2-1): encoded values in [0, 1] -> linear.

    Photographs (8-bit PNG/JPEG from cameras and phones) are sRGB-encoded; roomlight's own 8-bit
    previews use :data:`DISPLAY_GAMMA` instead. numpy in, float64 numpy out (any shape).
    """
    x = np.asarray(encoded, dtype=np.float64)
    return np.where(x <= 0.04045, x / 12.92, ((x + 0.055) / 1.055) ** 2.4)


def linear_to_srgb(linear):
    """The sRGB transfer function: linear values (clipped to [0, 1]) -> encoded values in [0, 1]."""
    x = np.clip(np.nan_to_num(np.asarray(linear, dtype=np.float64), nan=0.0, posinf=1.0), 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * x ** (1.0 / 2.4) - 0.055)
