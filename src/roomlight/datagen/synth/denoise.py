"""Optional denoising of rendered panoramas with Intel Open Image Denoise (PyPI ``pyoidn``).

The noisy HDR radiance is denoised with first-hit albedo and normal images
(:func:`roomlight.datagen.synth.camera.render_aovs`). Two safeguards keep the HDR content exact:

- **Light sources are not touched.** A pixel any of whose rays hits a light source (lamps,
  screens, windows) keeps its unbiased Monte Carlo value, so emitters are neither blurred
  nor changed in peak value; and the denoiser never sees them (they are filled in from
  their neighbourhood first), so their energy does not bleed into the pixels around them.
- **The longitude seam is continuous.** The panorama is padded by wrapping columns around
  before denoising and cropped afterwards.

``pyoidn`` is not a dependency of roomlight; :func:`denoise_available` says whether it can be
imported, and :func:`denoise_panorama` raises a :class:`RoomlightError` naming the fix.
"""

from __future__ import annotations

import numpy as np

from roomlight.core.color import luminance_np
from roomlight.errors import RoomlightError

__all__ = ["denoise_available", "denoise_panorama", "denoiser_version"]

_PAD = 16


def denoise_available() -> bool:
    """True when ``pyoidn`` can be imported."""
    try:
        import pyoidn  # noqa: F401 - probing only
    except (ImportError, OSError):
        return False
    return True


def denoiser_version() -> str:
    """``"pyoidn <version>"``, or raises like :func:`denoise_panorama`."""
    _import()
    from importlib.metadata import PackageNotFoundError, version

    try:
        return f"pyoidn {version('pyoidn')}"
    except PackageNotFoundError:  # pragma: no cover - installed without metadata
        return "pyoidn"


def _import():
    try:
        import pyoidn
    except (ImportError, OSError) as exc:
        raise RoomlightError(
            f"--denoise needs Intel Open Image Denoise's Python binding, which cannot be imported ({exc}); "
            "install it with `pip install pyoidn`, or render without --denoise") from exc
    return pyoidn


def _wrap(x: np.ndarray) -> np.ndarray:
    return np.concatenate([x[:, -_PAD:], x, x[:, :_PAD]], axis=1)


def _fill(x: np.ndarray, hole: np.ndarray, rounds: int = 64) -> np.ndarray:
    """Replace ``hole`` pixels of (H, W, 3) ``x`` by averages of their known neighbours
    (wrapping in longitude), growing inwards until every hole pixel is filled."""
    x = x.copy()
    known = ~hole
    if not known.any():
        return np.zeros_like(x)
    for _ in range(rounds):
        if known.all():
            break
        acc = np.zeros_like(x)
        cnt = np.zeros(x.shape[:2], np.float32)
        for dy, dx in ((0, 1), (0, -1), (1, 0), (-1, 0)):
            k = np.roll(known, (dy, dx), (0, 1))
            v = np.roll(x, (dy, dx), (0, 1))
            if dy == 1:
                k[0] = False
            if dy == -1:
                k[-1] = False
            acc += np.where(k[..., None], v, 0.0)
            cnt += k
        new = ~known & (cnt > 0)
        x[new] = acc[new] / cnt[new][:, None]
        known = known | new
    x[~known] = 0.0
    return x


def denoise_panorama(radiance: np.ndarray, albedo: np.ndarray, normal: np.ndarray,
                     emitter: np.ndarray) -> np.ndarray:
    """Denoise an (H, W, 3) HDR panorama, keeping light-source pixels unbiased.

    Args:
        radiance: (H, W, 3) float linear radiance (any positive scale).
        albedo: (H, W, 3) first-hit diffuse albedo in [0, 1].
        normal: (H, W, 3) first-hit world normals in [-1, 1].
        emitter: (H, W) fraction of each pixel's rays that hit a light source.
    Returns:
        (H, W, 3) float32 denoised radiance (>= 0).
    """
    oidn = _import()
    w = radiance.shape[1]
    if w < _PAD:
        raise RoomlightError(f"denoising needs panoramas at least {_PAD} pixels wide, got {w}")
    lights = np.asarray(emitter) > 0
    # OIDN expects HDR values of roughly unit brightness: normalise by the log-average.
    y = luminance_np(radiance)
    scale = float(np.exp(np.mean(np.log(y + 1e-6)))) or 1.0
    color = _wrap(_fill(np.asarray(radiance, np.float32) / np.float32(scale), lights))
    out = oidn.denoise(np.ascontiguousarray(color),
                       np.ascontiguousarray(_wrap(np.clip(albedo, 0, 1).astype(np.float32))),
                       np.ascontiguousarray(_wrap(np.clip(normal, -1, 1).astype(np.float32))),
                       hdr=True, quality="high")
    out = np.maximum(np.asarray(out, np.float32)[:, _PAD:_PAD + w] * np.float32(scale), 0.0)
    return np.where(lights[..., None], radiance, out).astype(np.float32)
