"""Procedural, tileable textures (numpy) that give the rooms' surfaces structure.

Each pattern is a pure function of its spec dict (``{"pattern": name, "seed": int, ...}``)
and a base colour; it returns an (n, n, 3) float32 array that tiles seamlessly (every random
field here is periodic: FFT-filtered noise, integer counts of planks and tiles), meant for a
Mitsuba ``bitmap`` with ``wrap_mode = repeat``. Albedo patterns return linear albedos in
[0, 0.95]; emission patterns (``screen``) return a multiplier with mean 1.

The spec's ``tile`` (metres covered by one repeat) is used by the mesh's uv scale, not here.
"""

from __future__ import annotations

import numpy as np

from roomlight.core.color import luminance_np
from roomlight.errors import RoomlightError

__all__ = ["PATTERNS", "make_texture", "periodic_noise"]


def periodic_noise(rng: np.random.Generator, n: int, beta: float = 2.0, cutoff: float = 1.0,
                   channels: int = 1) -> np.ndarray:
    """(n, n, channels) tileable noise with power spectrum ~ 1 / f^beta, zero mean, unit std.

    ``cutoff`` (cycles per tile) suppresses frequencies below it so the pattern has no
    tile-sized blobs.
    """
    white = rng.standard_normal((channels, n, n))
    f = np.fft.fftfreq(n) * n
    fr = np.sqrt(f[:, None] ** 2 + f[None, :] ** 2)
    filt = np.where(fr >= cutoff, np.maximum(fr, 1e-9) ** (-beta / 2.0), 0.0)
    out = np.real(np.fft.ifft2(np.fft.fft2(white) * filt))
    out -= out.mean(axis=(1, 2), keepdims=True)
    out /= out.std(axis=(1, 2), keepdims=True) + 1e-12
    return np.moveaxis(out, 0, -1)


def _finish(x: np.ndarray) -> np.ndarray:
    return np.clip(x, 0.0, 0.95).astype(np.float32)


def _noise(spec, base, rng, n):
    amp = float(spec.get("amplitude", 0.12))
    beta = float(spec.get("beta", 2.0))
    g = periodic_noise(rng, n, beta, 1.0, 1)
    tint = 1.0 + 0.15 * amp * periodic_noise(rng, n, beta, 1.0, 3)
    return _finish(base * np.exp(amp * g) * tint)


def _wood(spec, base, rng, n):
    planks = int(spec.get("planks", 4))  # plank rows per tile (along v)
    segments = int(spec.get("segments", 2))  # plank lengths per tile (along u)
    v = (np.arange(n) + 0.5) / n
    u = (np.arange(n) + 0.5) / n
    row = np.minimum((v * planks).astype(int), planks - 1)
    offsets = rng.uniform(0, 1, planks)
    uu = (u[None, :] + offsets[row][:, None]) % 1.0
    seg = np.minimum((uu * segments).astype(int), segments - 1)
    tones = np.exp(rng.normal(0.0, 0.18, (planks, segments)))
    tone = tones[row[:, None].repeat(n, 1), seg]
    grain_n = periodic_noise(rng, n, 2.5, 1.0, 1)[..., 0]
    local_v = (v * planks) % 1.0
    grain = 1.0 + 0.08 * np.sin(2 * np.pi * (6.0 * local_v[:, None] + 1.5 * grain_n + 3.0 * uu))
    seam = np.ones((n, n))
    edge = np.abs(((v * planks + 0.5) % 1.0) - 0.5) * n / planks < 0.7
    seam[edge, :] = 0.45
    ends = np.abs(((uu * segments + 0.5) % 1.0) - 0.5) * n / segments < 0.6
    seam[ends] = 0.5
    x = base * (tone * grain * seam)[..., None]
    return _finish(x)


def _tiles(spec, base, rng, n):
    count = int(spec.get("count", 4))
    grout = np.asarray(spec.get("grout", [0.5, 0.5, 0.48]), np.float64)
    second = spec.get("second")
    c = (np.arange(n) + 0.5) / n * count
    iy, ix = np.meshgrid(np.floor(c).astype(int), np.floor(c).astype(int), indexing="ij")
    tone = np.exp(rng.normal(0.0, 0.06, (count, count)))[iy, ix]
    col = np.broadcast_to(np.asarray(base, np.float64), (n, n, 3)).copy()
    if second is not None:
        checker = ((iy + ix) % 2 == 1)
        col[checker] = np.asarray(second, np.float64)
    col = col * tone[..., None] * (1.0 + 0.04 * periodic_noise(rng, n, 2.0, 2.0, 1))
    fx = np.abs(((c + 0.5) % 1.0) - 0.5)
    line = (fx[:, None] * n / count < 0.8) | (fx[None, :] * n / count < 0.8)
    col[line] = grout
    return _finish(col)


def _stripes(spec, base, rng, n):
    count = int(spec.get("count", 8))
    second = np.asarray(spec.get("second", np.asarray(base) * 0.8), np.float64)
    u = (np.arange(n) + 0.5) / n
    band = (np.floor(u * count) % 2 == 1)
    col = np.broadcast_to(np.asarray(base, np.float64), (n, n, 3)).copy()
    col[:, band] = second
    return _finish(col * (1.0 + 0.03 * periodic_noise(rng, n, 2.0, 1.0, 1)))


def _canvas(spec, base, rng, n):
    """An abstract painting: a few colours mixed by low-frequency noise."""
    k = int(spec.get("colors", 3))
    palette = rng.uniform(0.03, 0.8, (k, 3)) ** 1.3
    w = periodic_noise(rng, n, 3.0, 1.0, k) * 2.5
    w = np.exp(w - w.max(-1, keepdims=True))
    w /= w.sum(-1, keepdims=True)
    return _finish(w @ palette)


def _screen(spec, base, rng, n):
    """Emission multiplier of a screen showing something: smooth colour fields with mean 1."""
    col = np.exp(0.6 * periodic_noise(rng, n, 3.0, 1.0, 3))
    bright = np.exp(0.5 * periodic_noise(rng, n, 2.5, 1.0, 1))
    x = col * bright
    x /= luminance_np(x).mean()
    return x.astype(np.float32)


PATTERNS = {"noise": _noise, "wood": _wood, "tiles": _tiles, "stripes": _stripes,
            "canvas": _canvas, "screen": _screen}
_SIZES = {"wood": 256, "tiles": 128, "noise": 128, "stripes": 128, "canvas": 128, "screen": 64}


def make_texture(spec: dict, base=(1.0, 1.0, 1.0)) -> np.ndarray:
    """Render a pattern spec to an (n, n, 3) float32 array (see the module docstring).

    Args:
        spec: ``{"pattern": one of PATTERNS, "seed": int, ...pattern parameters}``; ``size``
            overrides the resolution n.
        base: linear RGB base colour (albedo patterns).
    """
    name = spec.get("pattern")
    if name not in PATTERNS:
        raise RoomlightError(f"texture pattern {name!r} is unknown; choose one of {', '.join(PATTERNS)}")
    n = int(spec.get("size", _SIZES[name]))
    rng = np.random.default_rng(int(spec.get("seed", 0)))
    return PATTERNS[name](spec, np.asarray(base, np.float64), rng, n)
