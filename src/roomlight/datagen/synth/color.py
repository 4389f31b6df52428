"""Colour helpers: light colour temperatures and plausible albedos, in linear Rec.709 RGB.

All colours here are linear Rec.709 (sRGB primaries) RGB, the colour space of the panoramas.
Luminance is Rec.709 Y = 0.2126 R + 0.7152 G + 0.0722 B.
"""

from __future__ import annotations

import math

import numpy as np

from roomlight.core.color import luminance_np

__all__ = ["hsv_albedo", "kelvin_rgb", "light_rgb", "luminance", "srgb_to_linear"]

_XYZ_TO_RGB = np.array([[3.2406, -1.5372, -0.4986],
                        [-0.9689, 1.8758, 0.0415],
                        [0.0557, -0.2040, 1.0570]])


def luminance(rgb) -> float:
    """Rec.709 luminance of a linear RGB triple."""
    return float(luminance_np(np.asarray(rgb, np.float64)))


def _lobe(lam, mu, s1, s2):
    s = np.where(lam < mu, s1, s2)
    return np.exp(-0.5 * ((lam - mu) / s) ** 2)


def _cie_xyz(lam: np.ndarray) -> np.ndarray:
    """CIE 1931 2-degree colour matching functions, multi-lobe Gaussian fit (Wyman et al. 2013)."""
    x = 1.056 * _lobe(lam, 599.8, 37.9, 31.0) + 0.362 * _lobe(lam, 442.0, 16.0, 26.7) \
        - 0.065 * _lobe(lam, 501.1, 20.4, 26.2)
    y = 0.821 * _lobe(lam, 568.8, 46.9, 40.5) + 0.286 * _lobe(lam, 530.9, 16.3, 31.1)
    z = 1.217 * _lobe(lam, 437.0, 11.8, 36.0) + 0.681 * _lobe(lam, 459.0, 26.0, 13.8)
    return np.stack([x, y, z], -1)


def kelvin_rgb(kelvin: float) -> tuple[float, float, float]:
    """Linear RGB of a blackbody at ``kelvin`` (1000-40000 K), scaled to luminance 1.

    Planck's law integrated against the CIE 1931 observer, converted XYZ -> linear Rec.709
    and clipped at 0 (very warm colours fall slightly outside the gamut).
    """
    t = float(np.clip(kelvin, 1000.0, 40000.0))
    lam = np.arange(380.0, 781.0, 5.0)
    c2 = 1.4388e-2  # m K
    planck = 1.0 / ((lam * 1e-9) ** 5 * np.expm1(c2 / (lam * 1e-9 * t)))
    xyz = (planck[:, None] * _cie_xyz(lam)).sum(0)
    rgb = np.clip(_XYZ_TO_RGB @ xyz, 0.0, None)
    rgb = rgb / luminance(rgb)
    return tuple(float(v) for v in rgb)  # type: ignore[return-value]


def light_rgb(kelvin: float, nits: float) -> tuple[float, float, float]:
    """Radiance (linear RGB) of a light of colour temperature ``kelvin`` and luminance ``nits``."""
    return tuple(float(v) * nits for v in kelvin_rgb(kelvin))  # type: ignore[return-value]


def srgb_to_linear(c):
    """sRGB-encoded values in [0, 1] -> linear (numpy array or scalar)."""
    c = np.asarray(c, np.float64)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def hsv_albedo(h: float, s: float, v: float) -> tuple[float, float, float]:
    """Linear albedo from hue (turns), saturation and value of the *sRGB-encoded* colour.

    Painters' colour choices are closer to uniform in the encoded space, so sampling there
    and linearising gives a natural spread. The result is clipped to [0.01, 0.92] (no real
    paint reflects more than ~92 % or less than ~1 %).
    """
    h = (h % 1.0) * 6.0
    i = math.floor(h) % 6
    f = h - math.floor(h)
    p, q, t = v * (1 - s), v * (1 - s * f), v * (1 - s * (1 - f))
    rgb = [(v, t, p), (q, v, p), (p, v, t), (p, q, v), (t, p, v), (v, p, q)][i]
    lin = np.clip(srgb_to_linear(np.array(rgb)), 0.01, 0.92)
    return tuple(float(x) for x in lin)  # type: ignore[return-value]
