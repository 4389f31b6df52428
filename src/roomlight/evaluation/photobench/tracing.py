"""Tracing a :class:`~roomlight.fitting.photo.camera.PhotoCamera` through a Mitsuba scene.

- :func:`trace_image`: path-traced radiance. Each pixel averages ``spp`` rays through points of
  its footprint drawn by a per-pixel stratified sampler (a box pixel filter), traced with the
  scene's own integrator (``integrator.sample``). Sums are formed in numpy (float64) in a fixed
  order, so an image is bit-identical for a given seed whatever Dr.Jit's thread count; this is
  what makes a benchmark build reproducible.
- :func:`trace_depth`: one ray through each pixel centre; ``scene.ray_intersect`` gives the
  distance t along the unit direction d, and the z-depth is ``t * (d . forward)``.
- :func:`trace_coverage`: for chosen shapes, the fraction of ``s x s`` stratified rays per pixel
  whose first hit (in the whole scene, so occluders count) is that shape.
"""

from __future__ import annotations

import numpy as np

from roomlight.errors import RoomlightError
from roomlight.fitting.photo.camera import PhotoCamera
from roomlight.core.render.raycast import shape_coverage
from roomlight.core.render.variant import mitsuba

__all__ = ["MAX_RAYS_PER_PASS", "trace_image", "trace_depth", "trace_coverage", "emitter_fraction", "camera_rays", "check_window"]

#: Rays traced per pass (bounds memory: ~100 bytes of state per ray).
MAX_RAYS_PER_PASS = 1 << 22


def camera_rays(mi, dr, camera: PhotoCamera, x, y):
    """Dr.Jit rays through film points (x, y) (``mi.Float`` pixel coordinates)."""
    m = camera.matrix
    c = lambda v: dr.opaque(mi.Float, float(v))  # noqa: E731 - opaque: one kernel for every camera
    qx = (x - c(camera.cx)) * c(1.0 / camera.fx)
    qy = -(y - c(camera.cy)) * c(1.0 / camera.fy)
    qz = mi.Float(-1.0)
    d = mi.Vector3f(*[c(m[k, 0]) * qx + c(m[k, 1]) * qy + c(m[k, 2]) * qz for k in range(3)])
    o = mi.Point3f(*[c(m[k, 3]) for k in range(3)])
    return mi.Ray3f(o, dr.normalize(d))


def trace_image(scene, camera: PhotoCamera, spp: int = 64, seed: int = 0, sampler: str = "multijitter",
                foreground=None, window=None) -> np.ndarray:
    """Path-traced image of ``scene`` (which holds its integrator) seen by ``camera``.

    Args:
        scene: ``mi.Scene`` with an integrator; spp: samples per pixel (stratified samplers round
            it up, see :func:`roomlight.datagen.synth.camera.effective_spp`); seed: any int.
        foreground: an optional ``mi.Scene`` of some of ``scene``'s shapes. A camera ray that hits
            one of them starts just in front of that hit instead of at the camera, so nothing else
            of ``scene`` can hide it (a light source's mesh that does not enclose the camera, say);
            other rays start at the camera.
        window: ``(x0, y0, w, h)``: render only these pixels (columns x0 .. x0 + w - 1, rows
            y0 .. y0 + h - 1): the same pixels as in the whole frame (other samples).
    Returns:
        (H, W, 3) float32 linear radiance, in the scene's emitter units; (h, w, 3) for a window.
    """
    import drjit as dr

    from roomlight.datagen.synth.camera import effective_spp

    mi = mitsuba()
    if spp <= 0:
        raise RoomlightError(f"render: spp must be positive, got {spp}")
    spp = effective_spp(spp, sampler)
    integrator = scene.integrator()
    x0, y0, w, h = check_window(camera, window)
    rows = max(1, min(h, MAX_RAYS_PER_PASS // (w * spp)))
    out = np.zeros((h, w, 3), np.float64)
    for k, r0 in enumerate(range(0, h, rows)):
        r1 = min(h, r0 + rows)
        n = (r1 - r0) * w * spp
        smp = mi.load_dict({"type": sampler, "sample_count": int(spp)})
        smp.set_samples_per_wavefront(int(spp))
        smp.seed(dr.opaque(mi.UInt32, (int(seed) * 7919 + k) & 0xFFFFFFFF), n)
        idx = dr.arange(mi.UInt32, n)
        pix = idx // spp
        i = pix // w + dr.opaque(mi.UInt32, r0 + y0)
        j = pix % w + dr.opaque(mi.UInt32, x0)
        s = smp.next_2d()
        ray = camera_rays(mi, dr, camera, mi.Float(j) + s.x, mi.Float(i) + s.y)
        if foreground is not None:
            hit = foreground.ray_intersect(ray)
            # back off by a relative 1e-4 so that the moved ray still meets the surface it found
            t0 = dr.select(hit.is_valid(), dr.maximum(hit.t * (1.0 - 1e-4) - 1e-6, 0.0), 0.0)
            ray = mi.Ray3f(ray.o + t0 * ray.d, ray.d)
        L, _, _ = integrator.sample(scene, smp, ray)
        L = mi.Color3f(L)
        dr.eval(L)
        rgb = np.stack([np.asarray(L[c], np.float32) for c in range(3)], -1)
        out[r0:r1] = rgb.reshape(r1 - r0, w, spp, 3).astype(np.float64).sum(2) / spp
    return out.astype(np.float32)


def check_window(camera: PhotoCamera, window) -> tuple[int, int, int, int]:
    """``(x0, y0, w, h)`` of a pixel window inside the camera's frame (the whole frame for None)."""
    if window is None:
        return 0, 0, camera.width, camera.height
    x0, y0, w, h = (int(v) for v in window)
    if not (0 <= x0 and 0 <= y0 and w > 0 and h > 0 and x0 + w <= camera.width and y0 + h <= camera.height):
        raise RoomlightError(f"render: window {window} is not inside the {camera.width}x{camera.height} frame")
    return x0, y0, w, h


def trace_depth(scene, camera: PhotoCamera) -> np.ndarray:
    """Exact z-depth (metres along the optical axis) at pixel centres; ``inf`` where a ray escapes.

    Returns:
        (H, W) float32.
    """
    import drjit as dr

    mi = mitsuba()
    x, y = camera.pixel_centres()
    ray = camera_rays(mi, dr, camera, mi.Float(x.astype(np.float32)), mi.Float(y.astype(np.float32)))
    si = scene.ray_intersect(ray)
    t = np.asarray(dr.select(si.is_valid(), si.t, dr.inf), np.float64)
    d = camera.directions(x, y)
    return (t * (d @ camera.forward)).astype(np.float32).reshape(camera.height, camera.width)


def trace_coverage(scene, camera: PhotoCamera, shapes: list, supersample: int = 4) -> np.ndarray:
    """Per-pixel coverage of each of ``shapes`` (Mitsuba shape objects of ``scene``).

    Returns:
        (K, H, W) float32: the fraction of a pixel's ``supersample**2`` rays (at stratified sub-pixel
        centres) whose first hit in ``scene`` is shape k.
    """
    import drjit as dr

    mi = mitsuba()
    s = int(supersample)
    return shape_coverage(scene, lambda x, y: camera_rays(mi, dr, camera, mi.Float((x / s).astype(np.float32)),
                                                          mi.Float((y / s).astype(np.float32))),
                          shapes, camera.width, camera.height, s, MAX_RAYS_PER_PASS)


def emitter_fraction(scene, camera: PhotoCamera) -> float:
    """The share of the frame's pixel centres whose ray first meets a light source: a lamp's or a
    window's emitting surface, or (rays that leave the scene) an environment emitter."""
    import drjit as dr

    mi = mitsuba()
    x, y = camera.pixel_centres()
    ray = camera_rays(mi, dr, camera, mi.Float(x.astype(np.float32)), mi.Float(y.astype(np.float32)))
    si = scene.ray_intersect(ray)
    lit = dr.select(si.is_valid(), si.shape.is_emitter(), scene.environment() is not None)
    return float(np.mean(np.asarray(lit, bool)))
