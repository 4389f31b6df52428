"""The outdoor environment seen through windows: sampling its parameters and evaluating it.

The model (parameters in :class:`roomlight.datagen.synth.spec.Sky`, radiance in nits, linear RGB):

- above the horizon: ``horizon + (zenith - horizon) * sin(e)^exponent`` (e = elevation; an
  exponent of 1 with horizon = zenith / 3 is the CIE overcast sky) plus a circumsolar glow;
- below the horizon: a diffuse ground, ``albedo * E_horizontal / pi``;
- a skyline of buildings/trees: per-azimuth obstruction heights with their own radiance;
- the sun: a disk of ``sun_radius_deg`` (0.5 deg by default, twice the real sun, to keep its
  sampling noise low at panorama resolution) whose radiance gives a physical illuminance
  E_sun = 30-100 klx (Meinel's air-mass model) at normal incidence.

:func:`sky_radiance` is written once against a tiny array API so the same code runs on numpy
(tests, previews) and inside the Dr.Jit emitter (:mod:`roomlight.datagen.synth.portal`).
"""

from __future__ import annotations

import math

import numpy as np

from roomlight.datagen.synth.color import kelvin_rgb, light_rgb, luminance
from roomlight.datagen.synth.spec import Sky

__all__ = [
    "SKYLINE_BINS",
    "SKY_KINDS",
    "NumpyOps",
    "SkyParams",
    "sample_sky",
    "sky_radiance",
    "sky_tables",
    "sun_solid_angle",
]

SKY_KINDS = ("clear", "overcast", "dusk", "night")
SKYLINE_BINS = 180


def sun_solid_angle(radius_deg: float) -> float:
    """Solid angle (sr) of a disk of angular radius ``radius_deg``."""
    return 2.0 * math.pi * (1.0 - math.cos(math.radians(radius_deg)))


def _scale(rgb, s):
    return tuple(float(c) * s for c in rgb)


def _skyline(rng: np.random.Generator, e_h: float, kind: str) -> tuple[list, list]:
    """Per-bin sin(elevation) of buildings/trees and their radiance (nits)."""
    heights = np.zeros(SKYLINE_BINS)
    facade = np.zeros((SKYLINE_BINS, 3))
    if rng.random() < 0.3:  # open view
        return heights.tolist(), facade.tolist()
    start = 0
    while start < SKYLINE_BINS:
        width = int(rng.integers(2, 16))
        stop = min(SKYLINE_BINS, start + width)
        if rng.random() < 0.75:
            elev = math.radians(rng.uniform(1.5, 22.0))
            heights[start:stop] = math.sin(elev)
            if rng.random() < 0.25:  # trees
                albedo = np.array([0.05, 0.09, 0.04]) * rng.uniform(0.6, 1.4)
            else:
                albedo = np.full(3, rng.uniform(0.12, 0.45)) * np.array(kelvin_rgb(rng.uniform(4500, 8000)))
            lit = e_h * rng.uniform(0.2, 1.0)
            rad = albedo * lit / math.pi
            if kind == "night":
                rad = rad + np.array(light_rgb(2700, 1.0)) * rng.uniform(0.0, 3.0)
            facade[start:stop] = rad
        start = stop
    return heights.tolist(), facade.tolist()


def sample_sky(rng: np.random.Generator, kind: str, sun_radius_deg: float = 0.5, sun_dir=None) -> Sky:
    """Random outdoor environment of the given kind (``clear``, ``overcast``, ``dusk``, ``night``).

    ``sun_dir`` (unit vector towards the sun, above the horizon) fixes the sun's direction of
    a clear sky instead of drawing it (used to put the sun in view of a window).

    Luminances (nits): clear zenith 0.8-8 k with a 1.3-2.5x brighter horizon and a sun of
    10-100 klx (clear to hazy); overcast zenith 0.3-10 k; dusk 10-400; night 0.005-1 with orange light pollution.
    """
    sun = None
    sun_dir = (0.0, 1.0, 0.0)
    glow = (0.0, 0.0, 0.0)
    glow_width = 0.3
    e_sun = 0.0
    if kind == "clear":
        lz = math.exp(rng.uniform(math.log(800.0), math.log(8000.0)))
        zenith = light_rgb(rng.uniform(12000, 25000), lz)
        horizon = light_rgb(rng.uniform(6500, 9000), lz * rng.uniform(1.3, 2.5))
        exponent = rng.uniform(0.3, 0.6)
        elev = math.radians(rng.uniform(8.0, 70.0))
        az = rng.uniform(0.0, 2.0 * math.pi)
        if sun_dir is not None:
            v = np.asarray(sun_dir, np.float64) / np.linalg.norm(sun_dir)
            elev, az = math.asin(float(v[1])), math.atan2(float(v[0]), -float(v[2]))
        sun_dir = (math.sin(az) * math.cos(elev), math.sin(elev), -math.cos(az) * math.cos(elev))
        air_mass = 1.0 / max(math.sin(elev), 0.05)
        # Meinel's clear-air model times a haze factor: from crisp (1.0) to hazy (0.35) days.
        e_sun = 1.2e5 * 0.7 ** (air_mass ** 0.678) * rng.uniform(0.35, 1.0)
        kelvin = 4000.0 + 1800.0 * math.sqrt(math.sin(elev))
        sun = light_rgb(kelvin, e_sun / sun_solid_angle(sun_radius_deg))
        glow = light_rgb(5500, lz * rng.uniform(2.0, 8.0))
        glow_width = rng.uniform(0.12, 0.3)
    elif kind == "overcast":
        lz = math.exp(rng.uniform(math.log(300.0), math.log(10000.0)))
        k = rng.uniform(6500, 7500)
        zenith = light_rgb(k, lz)
        horizon = light_rgb(k, lz / 3.0)
        exponent = 1.0
    elif kind == "dusk":
        lz = math.exp(rng.uniform(math.log(10.0), math.log(400.0)))
        zenith = light_rgb(rng.uniform(15000, 30000), lz)
        horizon = light_rgb(rng.uniform(2300, 3500), lz * rng.uniform(1.5, 4.0))
        exponent = rng.uniform(0.25, 0.5)
        az = rng.uniform(0.0, 2.0 * math.pi)
        sun_dir = (math.sin(az) * 0.999, -0.03, -math.cos(az) * 0.999)
        glow = light_rgb(2500, lz * rng.uniform(2.0, 6.0))
        glow_width = rng.uniform(0.3, 0.7)
    elif kind == "night":
        lz = math.exp(rng.uniform(math.log(0.005), math.log(1.0)))
        zenith = light_rgb(15000, lz)
        horizon = light_rgb(2200, lz * rng.uniform(1.0, 6.0))
        exponent = 0.5
    else:
        raise ValueError(f"sample_sky: unknown sky kind {kind!r}; choose one of {SKY_KINDS}")
    e_h = math.pi * 0.5 * (luminance(zenith) + luminance(horizon)) + e_sun * max(sun_dir[1], 0.0)
    ground_albedo = np.array([0.16, 0.15, 0.12]) * rng.uniform(0.5, 1.8)
    ground = tuple(float(x) for x in ground_albedo * e_h / math.pi)
    skyline, facade = _skyline(rng, e_h, kind)
    if sun is not None:
        az = math.atan2(sun_dir[0], -sun_dir[2]) % (2.0 * math.pi)
        b = min(int(az / (2.0 * math.pi) * SKYLINE_BINS), SKYLINE_BINS - 1)
        if skyline[b] >= sun_dir[1]:
            sun = None  # behind a building: no direct sun
    return Sky(kind=kind, zenith=zenith, horizon=horizon, exponent=float(exponent), ground=ground,
               glow=glow, glow_width=float(glow_width), sun=sun, sun_dir=tuple(float(v) for v in sun_dir),
               sun_radius_deg=float(sun_radius_deg), sun_illuminance=float(e_sun if sun is not None else 0.0),
               skyline=skyline, facade=facade)


class NumpyOps:
    """The array operations :func:`sky_radiance` needs, for numpy float64 arrays."""

    where = staticmethod(np.where)
    exp = staticmethod(np.exp)
    sqrt = staticmethod(np.sqrt)
    maximum = staticmethod(np.maximum)
    minimum = staticmethod(np.minimum)
    atan2 = staticmethod(np.arctan2)
    acos = staticmethod(lambda x: np.arccos(np.clip(x, -1.0, 1.0)))
    power = staticmethod(np.power)
    floor = staticmethod(np.floor)
    to_index = staticmethod(lambda x: np.floor(x).astype(np.int64))

    @staticmethod
    def gather(table, idx):
        return np.asarray(table)[idx]


class SkyParams:
    """The scalars of a :class:`Sky` in the form :func:`sky_radiance` reads them.

    ``convert`` turns each Python float into the array type wanted (identity for numpy; an
    opaque Dr.Jit scalar in the emitter, so that the compiled kernel does not depend on the
    values and is reused across rooms). An absent sun has zero radiance.
    """

    def __init__(self, sky: Sky, convert=float):
        c = convert
        self.zenith = [c(v) for v in sky.zenith]
        self.horizon = [c(v) for v in sky.horizon]
        self.ground = [c(v) for v in sky.ground]
        self.glow = [c(v) for v in sky.glow]
        self.sun = [c(v) for v in (sky.sun if sky.sun is not None else (0.0, 0.0, 0.0))]
        self.sun_dir = [c(v) for v in sky.sun_dir]
        self.exponent = c(sky.exponent)
        self.inv_glow_width = c(1.0 / sky.glow_width)
        self.cos_sun_radius = c(math.cos(math.radians(sky.sun_radius_deg)))


def sky_tables(sky: Sky) -> tuple[np.ndarray, ...]:
    """(skyline, facade_r, facade_g, facade_b) as float64 arrays of :data:`SKYLINE_BINS` bins."""
    fac = np.asarray(sky.facade, np.float64).reshape(-1, 3) if sky.facade else np.zeros((SKYLINE_BINS, 3))
    sk = np.asarray(sky.skyline, np.float64) if sky.skyline else np.zeros(SKYLINE_BINS)
    return sk, fac[:, 0].copy(), fac[:, 1].copy(), fac[:, 2].copy()


def sky_radiance(sky, x, y, z, ops=NumpyOps, tables=None, sun_mask=None):
    """Radiance (nits) arriving from unit directions (x, y, z) (world frame, y up).

    Args:
        sky: a :class:`Sky`, or its :class:`SkyParams` (required for non-numpy ``ops``).
        x, y, z: direction components (arrays of one shape), pointing *away* from the room.
        ops: array API (:class:`NumpyOps`, or the Dr.Jit one of the portal emitter).
        tables: :func:`sky_tables` arrays in the ops' type; computed from ``sky`` when None.
        sun_mask: which directions fall in the sun's disk, when the caller has decided it
            already (the portal emitter decides once so that its radiance and sampling pdf
            agree bit for bit at the disk's rim); default ``cos(angle to sun) > cos(radius)``.
    Returns:
        (r, g, b) arrays like ``x``.
    """
    if tables is None:
        tables = sky_tables(sky)
    p = SkyParams(sky) if isinstance(sky, Sky) else sky
    s = ops.maximum(y, 0.0)
    t = ops.power(ops.maximum(s, 1e-8), p.exponent)
    sx, sy, sz = p.sun_dir
    cos_sun = x * sx + y * sy + z * sz
    gamma = ops.acos(ops.minimum(ops.maximum(cos_sun, -1.0), 1.0))
    glow = ops.exp(-gamma * p.inv_glow_width)
    az = ops.atan2(x, -z) * (1.0 / (2.0 * math.pi))
    az = az - ops.floor(az)
    b = ops.to_index(ops.minimum(ops.maximum(az * SKYLINE_BINS, 0.0), SKYLINE_BINS - 0.5))
    skyline_h = ops.gather(tables[0], b)
    blocked = (y < skyline_h) & (y >= 0.0)
    below = y < 0.0
    in_sun = ((cos_sun > p.cos_sun_radius) if sun_mask is None else sun_mask) & ~blocked & ~below
    out = []
    for c in range(3):
        v = p.horizon[c] + (p.zenith[c] - p.horizon[c]) * t + p.glow[c] * glow
        v = ops.where(blocked, ops.gather(tables[1 + c], b), v)
        v = ops.where(below, p.ground[c] + 0.0 * v, v)
        v = ops.where(in_sun, p.sun[c] + 0.0 * v, v)
        out.append(v)
    return tuple(out)
