"""The tripod blind spot: finding it, and inpainting it in a gnomonic view centred on the nadir.

A camera on a tripod cannot see straight down: real captures have a black (zero) cap around the
nadir. :func:`detect_nadir_cap` measures its polar extent; :func:`inpaint_nadir` fills it:

1. map the panorama to display values with :class:`~roomlight.datagen.prepare.tonemap.DisplayMap`
   (exposure and white point measured outside the cap);
2. cut a square gnomonic view looking straight down whose field of view holds the cap and a
   ring of context around it (80 deg for caps up to 30 deg);
3. mark the view pixels that see the cap (plus one panorama row, because bilinear sampling near
   the cap's edge mixes in black pixels) and let the inpainter fill them;
4. paste the filled view back onto the cap's rows only (inverse gnomonic mapping), and add,
   with a cosine fade over the first ``feather`` rows, each column's difference between the
   real border row and the inpainted one there: the cap starts exactly where the border is and
   continues with the inpainted gradient, so there is no step at the seam;
5. invert the display mapping exactly on the cap.

Pixels outside the cap are copied, so they are bit-identical to the input.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import torch

from roomlight.core.color import luminance_np
from roomlight.errors import RoomlightError
from roomlight.core.geometry.projection import panorama_to_perspective, perspective_directions, perspective_to_panorama
from roomlight.datagen.prepare.tonemap import DisplayMap

__all__ = ["NadirResult", "cap_rows", "detect_nadir_cap", "inpaint_nadir", "nadir_view_fov"]

#: The nadir view looks straight down; its image "up" is -z (the direction of u = 0).
NADIR_FORWARD = (0.0, -1.0, 0.0)
NADIR_UP = (0.0, 0.0, -1.0)


def cap_rows(cap_deg: float, height: int) -> int:
    """Number of bottom rows whose span reaches into a cap of ``cap_deg`` degrees around the nadir."""
    if cap_deg <= 0:
        return 0
    return min(height, int(math.ceil(cap_deg * height / 180.0 - 1e-6)))


def detect_nadir_cap(radiance: np.ndarray, dark: float = 1e-3, core: float = 0.5) -> float:
    """Polar extent of a black blind spot at the bottom of a panorama, in degrees from the nadir (0: none).

    A pixel is dark when its luminance is at most ``dark`` x the panorama's median luminance.
    The cap is the run of bottom rows in which at least a fraction ``core`` of the pixels are dark
    (the bottom row must be one of them), extended upwards, by at most as many rows again, while
    a row has dark pixels touching (same or neighbouring column) the dark pixels just below them:
    the rim of a blind spot that is not centred on the pole, without the dark objects elsewhere
    in those rows. The result is a whole number of rows: ``rows x 180 / H``.

    Args:
        radiance: (H, W, 3) linear radiance.
    """
    y = luminance_np(np.asarray(radiance, np.float64))
    h = y.shape[0]
    med = float(np.median(y))
    if med <= 0:
        pos = y[y > 0]
        med = float(pos.mean()) if pos.size else 0.0
    if med <= 0:
        return 0.0  # an all-black panorama has no blind spot to speak of
    is_dark = y <= dark * med
    frac = is_dark.mean(axis=1)
    i = h - 1
    if frac[i] < core:
        return 0.0
    while i > 0 and frac[i - 1] >= core:
        i -= 1
    front, limit = is_dark[i], h - i
    while i > 0 and limit > 0:
        reach = front | np.roll(front, 1) | np.roll(front, -1)  # columns wrap around
        front = is_dark[i - 1] & reach
        if not front.any():
            break
        i -= 1
        limit -= 1
    return (h - i) * 180.0 / h


def nadir_view_fov(cap_deg: float) -> float:
    """Field of view (degrees) of the nadir view: the cap plus a ring of context half its size
    (at least 10 deg), never under 80 deg nor over 150 deg."""
    return float(min(150.0, max(80.0, 2.0 * (cap_deg + max(10.0, 0.5 * cap_deg)))))


@dataclass
class NadirResult:
    """What :func:`inpaint_nadir` did.

    Attributes:
        radiance: (H, W, 3) float32, the input with the cap filled.
        cap_deg: extent of the replaced cap (whole rows), degrees from the nadir.
        rows: number of replaced bottom rows.
        fov_deg, view_size: the nadir view.
        feather_rows: rows over which the seam correction fades out.
        display: the display mapping used (exposure, white, gamma).
        view: (s, s, 3) the inpainted view (display values), for previews.
        hole: (s, s) bool, the view pixels the inpainter filled.
    """

    radiance: np.ndarray
    cap_deg: float
    rows: int
    fov_deg: float
    view_size: int
    feather_rows: int
    display: DisplayMap
    view: np.ndarray
    hole: np.ndarray

    def summary(self) -> dict:
        return {"cap_deg": round(self.cap_deg, 4), "rows": self.rows, "view_fov_deg": self.fov_deg,
                "view_size": self.view_size, "feather_rows": self.feather_rows, "display": self.display.to_dict()}


def inpaint_nadir(radiance: np.ndarray, cap_deg: float, inpainter, *, view_size: int | None = None,
                  fov_deg: float | None = None, feather_rows: int | None = None) -> NadirResult:
    """Fill the cap of ``cap_deg`` degrees around the nadir (see the module docstring).

    Args:
        radiance: (H, W, 3) linear radiance, >= 0, W = 2H.
        cap_deg: the blind spot's extent from the nadir, degrees (every row reaching into it is replaced).
        inpainter: ``inpainter(image (s, s, 3) float32, mask (s, s) bool) -> (s, s, 3)``
            (:mod:`roomlight.datagen.prepare.inpainters`).
        view_size: the nadir view's size in pixels; default about twice the panorama's angular
            resolution (64..512).
        fov_deg: the nadir view's field of view; default :func:`nadir_view_fov`.
        feather_rows: rows over which the seam correction fades; default a third of the cap (>= 2).
    Returns:
        :class:`NadirResult`; rows above the cap are the input's, bit for bit.
    """
    rad = np.asarray(radiance)
    h, w = rad.shape[:2]
    n = cap_rows(cap_deg, h)
    if not 0 < n < h // 2:
        raise RoomlightError(f"nadir cap of {cap_deg:g} deg ({n} of {h} rows): expected a cap below the horizon")
    i0 = h - n  # first row of the cap
    cap = n * math.pi / h  # the replaced rows' extent, radians from the nadir
    keep = np.zeros((h, w), bool)
    keep[:i0] = True
    dmap = DisplayMap.fit(rad, mask=keep)
    disp = dmap.forward(rad)
    fov = float(fov_deg) if fov_deg else nadir_view_fov(math.degrees(cap))
    if math.radians(fov) / 2.0 <= cap + 2.0 * math.pi / h:
        raise RoomlightError(f"nadir view of {fov:g} deg cannot hold a cap of {math.degrees(cap):.1f} deg")
    size = int(view_size) if view_size else int(min(512, max(64, round(4.0 * math.tan(math.radians(fov) / 2.0) * h / math.pi))))

    pano = torch.from_numpy(np.ascontiguousarray(disp.transpose(2, 0, 1)))[None]
    view = panorama_to_perspective(pano, size, size, fov, NADIR_FORWARD, NADIR_UP)[0].permute(1, 2, 0).numpy()
    dirs = perspective_directions(size, size, fov, NADIR_FORWARD, NADIR_UP, dtype=torch.float64).numpy()
    from_nadir = np.arccos(np.clip(-dirs[..., 1], -1.0, 1.0))
    # bilinear samples within one row of the cap's edge mix in its black pixels: fill those too
    hole = from_nadir < cap + math.pi / h
    filled = np.asarray(inpainter(view.astype(np.float32), hole.copy()), np.float64)
    if filled.shape != view.shape:
        raise RoomlightError(f"the inpainter returned shape {filled.shape} for a view of shape {view.shape}")
    if not np.isfinite(filled[hole]).all():
        raise RoomlightError("the inpainter returned NaN or infinite values")
    view_out = np.where(hole[..., None], np.maximum(filled, 0.0), view)

    back, inside = perspective_to_panorama(torch.from_numpy(np.ascontiguousarray(view_out.transpose(2, 0, 1)))[None],
                                           h, fov, NADIR_FORWARD, NADIR_UP)
    back = back[0].permute(1, 2, 0).numpy()
    if not inside.numpy()[i0 - 1:].all():
        raise RoomlightError("the nadir view does not cover the cap (internal error)")
    f = int(feather_rows) if feather_rows else max(2, n // 3)
    f = max(1, min(f, n))
    k = np.arange(n, dtype=np.float64)
    fade = np.where(k < f, 0.5 * (1.0 + np.cos(math.pi * k / f)), 0.0)
    offset = disp[i0 - 1] - back[i0 - 1]  # (W, 3): real border row minus its inpainted version
    cap_disp = np.maximum(back[i0:] + fade[:, None, None] * offset[None], 0.0)

    out = rad.astype(np.float32, copy=True)
    out[i0:] = dmap.inverse(cap_disp).astype(np.float32)
    return NadirResult(out, n * 180.0 / h, n, fov, size, f, dmap, view_out.astype(np.float32), hole)
