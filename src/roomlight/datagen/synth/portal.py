"""Window portals: an area emitter in the window opening that shows the outdoor environment.

A window is a rectangle in the opening (facing into the room) whose emitted radiance depends
on the *direction* of the ray leaving the room through it: ``L(d) = sky(d)`` with sky, ground,
skyline and sun of :mod:`roomlight.datagen.synth.sky` at infinity. From any point in the room this is
exactly what an open window onto a distant environment shows, and light only enters through
the opening, so next-event estimation wastes no samples on the rest of the sphere (what an
environment map outside the building would do).

Direction sampling from a reference point p is a two-strategy mixture:
- area: a uniform point on the rectangle (pdf = dist^2 / (cos * area) in solid angle);
- sun: a uniform direction in the sun's cone, kept when it passes through the rectangle
  (probability ``sun_fraction``, chosen from the sun's and sky's flux through the window).
:meth:`pdf_direction` returns the same mixture, so Mitsuba's MIS between emitter and BSDF
sampling stays consistent. Radiance is zero on the back side.
"""

from __future__ import annotations

import math

import numpy as np

from roomlight.datagen.synth.sky import SkyParams, sky_radiance, sky_tables, sun_solid_angle
from roomlight.datagen.synth.spec import Sky, Window

__all__ = ["portal_emitter", "portal_power", "portal_quad"]

_CLASSES: dict[str, type] = {}


def portal_quad(w: Window) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(origin, edge_a, edge_b) of the portal rectangle: the window hole moved ``depth``
    outwards, oriented so that edge_a x edge_b points into the room."""
    n = np.asarray(w.normal, np.float64)
    o = np.asarray(w.origin, np.float64) - n * w.depth
    a = np.asarray(w.edge_a, np.float64)
    b = np.asarray(w.edge_b, np.float64)
    if np.dot(np.cross(a, b), n) < 0:
        o, a = o + a, -a
    return o, a, b


def portal_power(w: Window, sky: Sky) -> tuple[float, float]:
    """Rough (sky, sun) luminous flux through the window (lm-like), for sampling weights."""
    from roomlight.datagen.synth.color import luminance

    _, a, b = portal_quad(w)
    area = float(np.linalg.norm(np.cross(a, b)))
    l_sky = (luminance(sky.zenith) + luminance(sky.horizon) + luminance(sky.ground)) / 3.0
    sky_flux = math.pi * area * l_sky
    sun_flux = 0.0
    if sky.sun is not None:
        cos = -float(np.dot(np.asarray(sky.sun_dir), np.asarray(w.normal)))
        sun_flux = area * sky.sun_illuminance * max(cos, 0.0)
    return sky_flux, sun_flux


class _DrJitOps:
    """:func:`roomlight.datagen.synth.sky.sky_radiance`'s array API on Dr.Jit types."""

    def __init__(self, mi, dr):
        self.mi, self.dr = mi, dr

    def where(self, c, a, b):
        Float = self.mi.Float
        return self.dr.select(c, a if not isinstance(a, (int, float)) else Float(a),
                              b if not isinstance(b, (int, float)) else Float(b))

    def exp(self, x):
        return self.dr.exp(x)

    def sqrt(self, x):
        return self.dr.sqrt(x)

    def maximum(self, a, b):
        return self.dr.maximum(a, b)

    def minimum(self, a, b):
        return self.dr.minimum(a, b)

    def atan2(self, y, x):
        return self.dr.atan2(y, x)

    def acos(self, x):
        return self.dr.safe_acos(x)

    def power(self, x, p):
        return self.dr.power(x, p)

    def floor(self, x):
        return self.dr.floor(x)

    def to_index(self, x):
        return self.mi.UInt32(x)

    def gather(self, table, idx):
        return self.dr.gather(self.mi.Float, table, idx)


def _portal_class(mi):
    import drjit as dr

    variant = mi.variant()
    if variant in _CLASSES:
        return _CLASSES[variant]

    def scalar(v: float):
        # Opaque: the value lives in memory, so kernels compiled for one room serve all rooms.
        return dr.opaque(mi.Float, float(v))

    def vec3(v, cls=mi.Vector3f):
        return cls(*[scalar(c) for c in v])

    class PortalEmitter(mi.Emitter):
        """Area emitter on a window rectangle radiating the outdoor environment (see module)."""

        def __init__(self, props):
            mi.Emitter.__init__(self, props)
            self.m_flags = mi.EmitterFlags.Surface | mi.EmitterFlags.SpatiallyVarying

        def configure(self, window: Window, sky: Sky):
            o, a, b = portal_quad(window)
            n = np.cross(a, b)
            area = float(np.linalg.norm(n))
            self.kind = sky.kind
            self.o, self.a, self.b = vec3(o, mi.Point3f), vec3(a), vec3(b)
            self.n = vec3(n / area)
            self.area = scalar(area)
            self.inv_area = scalar(1.0 / area)
            self.inv_a2 = scalar(1.0 / float(np.dot(a, a)))
            self.inv_b2 = scalar(1.0 / float(np.dot(b, b)))
            sky_flux, sun_flux = portal_power(window, sky)
            q = sun_flux / (sun_flux + sky_flux) if sky.sun is not None and sun_flux > 0 else 0.0
            q = float(np.clip(q, 0.2, 0.8)) if q > 0 else 0.0
            self.has_sun = q > 0
            self.q = scalar(q)
            self.one_minus_q = scalar(1.0 - q)
            self.inv_q = scalar(1.0 / q if q > 0 else 0.0)
            self.inv_one_minus_q = scalar(1.0 / (1.0 - q))
            self.cos_sun = scalar(math.cos(math.radians(sky.sun_radius_deg)))
            self.cone_pdf = scalar(1.0 / sun_solid_angle(sky.sun_radius_deg))
            self.sun_dir = vec3(sky.sun_dir)
            self.params = SkyParams(sky, scalar)
            self.tables = tuple(mi.Float(np.ascontiguousarray(t, np.float32)) for t in sky_tables(sky))
            self.ops = _DrJitOps(mi, dr)
            return self

        # -- radiance -------------------------------------------------------------------------
        def _in_cone(self, d):
            # The one place that decides "inside the sun's disk": radiance and pdf must agree
            # exactly at the rim, where the sun strategy puts many of its samples.
            s = self.sun_dir
            return d.x * s.x + d.y * s.y + d.z * s.z > self.cos_sun

        def _radiance(self, d, in_cone=None):
            mask = self._in_cone(d) if in_cone is None else in_cone
            r, g, b = sky_radiance(self.params, d.x, d.y, d.z, self.ops, self.tables, sun_mask=mask)
            return mi.Color3f(r, g, b)

        def eval(self, si, active=True):
            d = -si.to_world(si.wi)
            front = active & (mi.Frame3f.cos_theta(si.wi) > 0)
            return dr.select(front, self._radiance(d), mi.Color3f(0.0))

        # -- sampling -------------------------------------------------------------------------
        def _pdf(self, d, dist, cos_l, in_cone=None):
            pa = dr.select(cos_l > 0, dist * dist * self.inv_area / dr.maximum(cos_l, 1e-12), 0.0)
            in_cone = self._in_cone(d) if in_cone is None else in_cone
            return self.one_minus_q * pa + dr.select(in_cone, self.q * self.cone_pdf, 0.0)

        def sample_direction(self, it, sample, active=True):
            use_sun = sample.x < self.q
            sx = dr.select(use_sun, sample.x * self.inv_q, (sample.x - self.q) * self.inv_one_minus_q)
            s2 = mi.Point2f(dr.clip(sx, 0.0, 0.99999994), sample.y)
            p = self.o + self.a * s2.x + self.b * s2.y
            # Sun strategy: a direction in the sun's cone, kept if it leaves through the window.
            dl = mi.warp.square_to_uniform_cone(s2, self.cos_sun)
            dsun = mi.Frame3f(self.sun_dir).to_world(dl)
            denom = dr.dot(dsun, self.n)
            t = dr.dot(self.o - it.p, self.n) / dr.select(denom != 0, denom, 1e-20)
            ps = it.p + dsun * t
            rel = ps - self.o
            u = dr.dot(rel, self.a) * self.inv_a2
            v = dr.dot(rel, self.b) * self.inv_b2
            hit = (t > 0) & (u >= 0) & (u <= 1) & (v >= 0) & (v <= 1)
            p = dr.select(use_sun, ps, p)
            valid = mi.Bool(active) & (~use_sun | hit)
            dv = p - it.p
            dist = dr.norm(dv)
            # The sun strategy keeps its sampled direction (re-deriving it from the point would
            # move it by rounding, and at the disk's rim in or out of the disk).
            d = dr.select(use_sun, dsun, dv / dr.maximum(dist, 1e-12))
            cos_l = -dr.dot(d, self.n)
            in_cone = self._in_cone(d)
            pdf = self._pdf(d, dist, cos_l, in_cone)
            valid &= (cos_l > 0) & (pdf > 0)
            ds = dr.zeros(mi.DirectionSample3f)
            ds.p = p
            ds.n = self.n
            ds.uv = s2
            ds.time = it.time
            ds.pdf = dr.select(valid, pdf, 0.0)
            ds.delta = mi.Bool(False)
            ds.d = d
            ds.dist = dist
            weight = dr.select(valid, self._radiance(d, in_cone) / dr.select(valid, pdf, 1.0), mi.Color3f(0.0))
            return ds, mi.Spectrum(weight)

        def pdf_direction(self, it, ds, active=True):
            cos_l = -dr.dot(ds.d, self.n)
            return dr.select(active, self._pdf(ds.d, ds.dist, cos_l), 0.0)

        def sample_wavelengths(self, si, sample, active=True):
            return dr.zeros(mi.Wavelength), mi.Spectrum(1.0)

        def sample_position(self, time, sample, active=True):
            ps = dr.zeros(mi.PositionSample3f)
            ps.p = self.o + self.a * sample.x + self.b * sample.y
            ps.n = self.n
            ps.uv = sample
            ps.time = time
            ps.pdf = self.inv_area
            ps.delta = mi.Bool(False)
            return ps, mi.Float(1.0)

        def pdf_position(self, ps, active=True):
            return self.inv_area

        def traverse(self, callback):
            pass

        def parameters_changed(self, keys=None):
            pass

        def to_string(self):
            return f"PortalEmitter[sky={self.kind}, sun={self.has_sun}]"

    _CLASSES[variant] = PortalEmitter
    return PortalEmitter


def portal_emitter(mi, window: Window, sky: Sky, sampling_weight: float = 1.0):
    """A portal emitter object for ``window`` under ``sky`` (attach it to the portal mesh)."""
    cls = _portal_class(mi)
    props = mi.Properties()
    props["sampling_weight"] = float(sampling_weight)
    return cls(props).configure(window, sky)
