"""The equirectangular camera: path-traced radiance and exact radial depth panoramas.

Mitsuba 3 has no spherical sensor, so rays are generated here (the convention of docs/conventions.md via
:func:`roomlight.core.geometry.pixel_directions`'s formula) and traced with
``integrator.sample(scene, sampler, ray)``.

- Radiance: each pixel averages ``spp`` rays, uniformly distributed in *solid angle* over the
  pixel's cell (jitter in azimuth and in cos(theta)), drawn from a per-pixel stratified
  sampler (``multijitter`` by default: every 2-D sample dimension is stratified across the
  pixel's samples). Sums are formed in numpy (float64) in a fixed order, so results are
  bit-identical for a given seed whatever Dr.Jit's thread count.
- Depth: one ray through each pixel centre; ``scene.ray_intersect`` gives the distance along
  the unit direction, i.e. the radial depth in metres.

The panorama frame is the world frame rotated by ``yaw`` about +y: pixel direction omega maps
to the world direction ``R_y(yaw) omega`` (x' = cos(yaw) x + sin(yaw) z, z' = -sin(yaw) x + cos(yaw) z).
"""

from __future__ import annotations

import math

import numpy as np

from roomlight.errors import RoomlightError
from roomlight.core.render.variant import mitsuba

__all__ = ["MAX_RAYS_PER_PASS", "SAMPLERS", "effective_spp", "render_aovs", "render_depth", "render_radiance"]

SAMPLERS = ("multijitter", "independent", "stratified", "orthogonal", "ldsampler")
#: Rays traced per pass (bounds memory: ~100 bytes of state per ray).
MAX_RAYS_PER_PASS = 1 << 22


def _directions(mi, dr, rows, width: int, height: int, yaw: float, su=None, sv=None):
    """World directions for pixels of the given rows (UInt32 row, col arrays) with offsets
    (su, sv) in [0, 1)^2 in azimuth and cos(theta) (None = pixel centre)."""
    i, j = rows
    u = (mi.Float(j) + (su if su is not None else 0.5)) * (1.0 / width)
    phi = 2.0 * math.pi * u
    if sv is None:
        theta = (mi.Float(i) + 0.5) * (math.pi / height)
        cos_t, sin_t = dr.cos(theta), dr.sin(theta)
    else:
        c0 = dr.cos(mi.Float(i) * (math.pi / height))
        c1 = dr.cos((mi.Float(i) + 1.0) * (math.pi / height))
        cos_t = c0 + (c1 - c0) * sv
        sin_t = dr.sqrt(dr.maximum(1.0 - cos_t * cos_t, 0.0))
    x = dr.sin(phi) * sin_t
    z = -dr.cos(phi) * sin_t
    cy, sy = dr.opaque(mi.Float, math.cos(yaw)), dr.opaque(mi.Float, math.sin(yaw))
    return mi.Vector3f(cy * x + sy * z, cos_t, -sy * x + cy * z)


def _origin(mi, dr, origin):
    # Opaque so that the compiled kernel does not depend on the capture point.
    return mi.Point3f(*[dr.opaque(mi.Float, float(v)) for v in origin])


def _check(height: int, width: int, spp: int):
    if height <= 0 or width != 2 * height:
        raise RoomlightError(f"panorama resolution must be H x 2H with H > 0, got {height}x{width}")
    if spp <= 0:
        raise RoomlightError(f"spp must be a positive integer, got {spp}")


def effective_spp(spp: int, sampler: str = "multijitter") -> int:
    """Samples per pixel the sampler really takes for a request of ``spp`` (stratified
    samplers round up to a grid: multijitter 128 -> 132, stratified to a square)."""
    if sampler not in SAMPLERS:
        raise RoomlightError(f"sampler {sampler!r} is unknown; choose one of {', '.join(SAMPLERS)}")
    if spp <= 0:
        raise RoomlightError(f"spp must be a positive integer, got {spp}")
    mi = mitsuba()
    level = mi.log_level()
    try:
        mi.set_log_level(mi.LogLevel.Error)
        return int(mi.load_dict({"type": sampler, "sample_count": int(spp)}).sample_count())
    finally:
        mi.set_log_level(level)


def render_radiance(scene, origin, height: int = 128, width: int | None = None, spp: int = 64,
                    seed: int = 0, yaw: float = 0.0, sampler: str = "multijitter") -> np.ndarray:
    """Path-traced equirectangular radiance seen from ``origin``.

    Args:
        scene: ``mi.Scene`` with an integrator (see :func:`roomlight.datagen.synth.scene.build_scene`).
        origin: capture point (x, y, z), world frame, metres.
        height, width: panorama size (W = 2H; width defaults to 2 * height).
        spp: samples per pixel (rounded up as the sampler needs: see :func:`effective_spp`).
        seed: sampler seed (any int; the same seed gives identical output).
        yaw: rotation of the panorama frame about +y (radians; see the module docstring).
        sampler: Mitsuba sampler plugin, one of :data:`SAMPLERS`.
    Returns:
        (H, W, 3) float32 linear RGB radiance (same units as the scene's emitters).
    """
    import drjit as dr

    mi = mitsuba()
    width = width or 2 * height
    _check(height, width, spp)
    spp = effective_spp(spp, sampler)
    integrator = scene.integrator()
    rows_per_pass = max(1, min(height, MAX_RAYS_PER_PASS // (width * spp)))
    out = np.zeros((height, width, 3), np.float64)
    o = _origin(mi, dr, origin)
    for k, r0 in enumerate(range(0, height, rows_per_pass)):
        r1 = min(height, r0 + rows_per_pass)
        n_pix = (r1 - r0) * width
        n = n_pix * spp
        smp = mi.load_dict({"type": sampler, "sample_count": int(spp)})
        smp.set_samples_per_wavefront(int(spp))
        smp.seed(dr.opaque(mi.UInt32, (int(seed) * 7919 + k) & 0xFFFFFFFF), n)
        idx = dr.arange(mi.UInt32, n)
        pix = idx // spp
        i = pix // width + dr.opaque(mi.UInt32, r0)
        j = pix % width
        s = smp.next_2d()
        d = _directions(mi, dr, (i, j), width, height, yaw, s.x, s.y)
        ray = mi.Ray3f(o, d)
        L, _, _ = integrator.sample(scene, smp, ray)
        L = mi.Color3f(L)
        dr.eval(L)  # one kernel for all three channels
        rgb = np.stack([np.asarray(L[c], np.float32) for c in range(3)], -1)
        out[r0:r1] = rgb.reshape(r1 - r0, width, spp, 3).astype(np.float64).sum(2) / spp
    return out.astype(np.float32)


def render_depth(scene, origin, height: int = 128, width: int | None = None, yaw: float = 0.0) -> np.ndarray:
    """Exact radial depth (metres) at pixel centres; ``inf`` where a ray escapes.

    Returns:
        (H, W) float32.
    """
    import drjit as dr

    mi = mitsuba()
    width = width or 2 * height
    _check(height, width, 1)
    n = height * width
    idx = dr.arange(mi.UInt32, n)
    d = _directions(mi, dr, (idx // width, idx % width), width, height, yaw)
    si = scene.ray_intersect(mi.Ray3f(_origin(mi, dr, origin), d))
    t = dr.select(si.is_valid(), si.t, dr.inf)
    return np.asarray(t, np.float32).reshape(height, width)


def render_aovs(scene, origin, height: int = 128, width: int | None = None, spp: int = 16,
                seed: int = 0, yaw: float = 0.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """First-hit auxiliary images for denoising, averaged over ``spp`` jittered rays per pixel.

    Returns:
        ``(albedo (H, W, 3), normal (H, W, 3), emitter (H, W))`` float32: the diffuse
        reflectance and world shading normal at the first hit, and the fraction of the pixel's
        rays whose first hit is a light source (an area emitter or a window portal).
    """
    import drjit as dr

    mi = mitsuba()
    width = width or 2 * height
    _check(height, width, spp)
    n = height * width * spp
    smp = mi.load_dict({"type": "independent", "sample_count": int(spp)})
    smp.seed(dr.opaque(mi.UInt32, (int(seed) * 7919 + 104729) & 0xFFFFFFFF), n)
    idx = dr.arange(mi.UInt32, n)
    pix = idx // spp
    s = smp.next_2d()
    d = _directions(mi, dr, (pix // width, pix % width), width, height, yaw, s.x, s.y)
    ray = mi.Ray3f(_origin(mi, dr, origin), d)
    si = scene.ray_intersect(ray)
    albedo = mi.Color3f(si.bsdf(ray).eval_diffuse_reflectance(si))
    normal = dr.select(si.is_valid(), si.sh_frame.n, mi.Vector3f(0.0))
    emitter = mi.Float(si.emitter(scene) != None)
    dr.eval(albedo, normal, emitter)

    def mean(v, c):
        a = np.stack([np.asarray(v[k], np.float32) for k in range(c)], -1)
        return a.reshape(height, width, spp, c).astype(np.float64).mean(2).astype(np.float32)

    em = np.asarray(emitter, np.float32).reshape(height, width, spp).mean(2)
    return mean(albedo, 3), mean(normal, 3), em.astype(np.float32)
