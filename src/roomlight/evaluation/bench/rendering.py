"""Rendering a scene view under an emitter at high spp, and the view's object masks.

Both the benchmark builder (ground truth) and the runner (renders under recovered emitters) go
through :func:`render_view`, so the two differ only in the emitter and the seed.

High sample counts are split into passes of at most ``max_samples`` paths (pixels x spp) whose
images are averaged: one Mitsuba wavefront of 1000 x 1000 pixels at 4096 spp (the paper's
setting) would need ~4e9 paths in memory at once.

Masks come from casting the view camera's primary rays against the view's objects alone
(``scene.ray_intersect``; no emitter), ``supersample`` x ``supersample`` rays per pixel.
"""

from __future__ import annotations

import numpy as np
import torch

from roomlight.core.render.raycast import MAX_SAMPLES_PER_PASS, render_in_passes, shape_coverage

__all__ = ["MAX_SAMPLES_PER_PASS", "render_passes", "view_emitter_scene", "render_view", "object_coverage"]


def render_passes(escene, spp: int, seed: int = 0, max_samples: int = MAX_SAMPLES_PER_PASS) -> torch.Tensor:
    """Render an :class:`~roomlight.core.render.scene.EmitterScene` at ``spp`` in averaged passes
    (:func:`~roomlight.core.render.raycast.render_in_passes`).

    Returns:
        (H, W, 3) float32 linear radiance.
    """
    film = escene.scene.sensors()[0].film().crop_size()
    return render_in_passes(lambda n, sd: escene.render(spp=n, seed=sd).double(), spp, int(film[0]) * int(film[1]),
                            seed, max_samples).float()


def view_emitter_scene(scene, view, kind, resolution, max_depth: int = 4):
    """An EmitterScene of ``view``'s objects and camera with an emitter of ``kind`` at ``resolution``."""
    from roomlight.core.render.scene import EmitterScene
    from roomlight.fitting.scene.build import view_objects

    v = scene.view(view) if isinstance(view, str) else view
    return EmitterScene(kind, tuple(resolution), objects=view_objects(scene, v), sensor=v.camera.sensor(),
                        integrator={"type": "prb", "max_depth": int(max_depth)})


def render_view(scene, view, radiance: torch.Tensor, depth: torch.Tensor | None, kind: str = "mesh",
                spp: int = 256, seed: int = 0, max_depth: int = 4) -> torch.Tensor:
    """Render a view of a scene description under an emitter.

    Args:
        scene: a :class:`~roomlight.fitting.scene.SceneSpec`; view: its view name or ViewSpec.
        radiance: (H, W, 3) linear emitter radiance; depth: (H, W) metres (None for env maps).
        kind: ``mesh``, ``envmap`` or ``sphere:R``.
    Returns:
        (h, w, 3) float32 linear render at the view camera's resolution.
    """
    es = view_emitter_scene(scene, view, kind, radiance.shape[:2], max_depth)
    es.set_emitter(radiance.float(), None if depth is None else depth.float())
    return render_passes(es, spp, seed)


def object_coverage(scene, view, supersample: int = 4) -> tuple[np.ndarray, np.ndarray]:
    """Per-pixel coverage of a view's objects, by ray casting the view camera.

    Args:
        scene: a SceneSpec; view: a view name or ViewSpec.
        supersample: rays per pixel along each axis (stratified at sub-pixel centres).
    Returns:
        coverage: (h, w) float32, fraction of a pixel's rays that hit any of the view's objects;
        ids: (h, w) int32, 1 + index (in ``view.objects``) of the object hit by most of the
        pixel's rays, 0 where none is hit.
    """
    from roomlight.core.render.variant import mitsuba
    from roomlight.fitting.scene.build import view_objects

    mi = mitsuba()
    v = scene.view(view) if isinstance(view, str) else view
    objs = view_objects(scene, v)
    ms = mi.load_dict({"type": "scene", "sensor": v.camera.sensor(), **objs})
    sensor = ms.sensors()[0]
    w, h, s = v.camera.width, v.camera.height, int(supersample)

    def rays(x, y):  # the sensor's film coordinates are [0, 1] across the frame
        pos = mi.Point2f(mi.Float((x / (w * s)).astype(np.float32)), mi.Float((y / (h * s)).astype(np.float32)))
        return sensor.sample_ray(0.0, 0.5, pos, mi.Point2f(0.5, 0.5))[0]

    counts = shape_coverage(ms, rays, [objs[oid] for oid in v.objects], w, h, s)
    coverage = counts.sum(0)
    ids = np.where(coverage > 0, counts.argmax(0) + 1, 0).astype(np.int32)
    return np.clip(coverage, 0.0, 1.0), ids
