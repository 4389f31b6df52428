"""The three-sphere protocol's images: the input crop, the panoramas scored, the spheres rendered.

- **The crop** (:func:`make_crop`): the panorama tone-mapped as a whole (:data:`CROP_TONEMAP`: gamma 2.4,
  the 99th percentile of its non-zero values at 0.9, clipped), then viewed by a level pinhole camera at
  its centre looking at the middle of the image (+z in roomlight's axes), vertical field of view 60°,
  4:3, 256 x 192 pixels (:data:`CROP_SIZE`), sampled bilinearly. Saved as an 8-bit PNG: a photograph.
- **The panoramas scored** (:func:`score_panorama`): the prediction and the truth each resized to
  128 x 256 (antialiased) and normalised on their own (:data:`SCORE_TONEMAP`: E' = alpha E^(1/2.4), alpha
  = 0.5 / the median of the non-zero values), so no method is judged on its absolute exposure.
- **The spheres** (:func:`render_spheres`): three unit spheres, one at a time, at the panorama's centre
  under it as an environment map, seen along the crop's direction from 16 units away (the field's
  camera; roomlight frames the sphere to fill its 128 x 128 image instead of an 85 mm lens's 30 %, which
  changes how many pixels sample it, not what they show), rendered by Mitsuba (``path``, 2 bounces):

  - ``diffuse``: principled, base colour 0.8, roughness 0.364, specular 0.5, not metallic;
  - ``matte``: a rough silver: principled, base colour 0.8, metallic, roughness 0.327 (the field mixes
    it with a glossy lobe of roughness 0.369 through a Fresnel factor of IOR 6.55, which Mitsuba's
    principled BSDF has no node for);
  - ``mirror``: a perfect conductor of reflectance 0.8 (the field's principled metallic base 0.8 at
    roughness 0, whose Schlick Fresnel is 0.8 at normal incidence and rises towards 1 at grazing angles).

  The scores are computed over the sphere's mask: the pixels whose centre ray meets the sphere.
"""

from __future__ import annotations

import math

import numpy as np
import torch

from roomlight.evaluation.crops.metrics import CROP_TONEMAP, SCORE_TONEMAP, tonemap

__all__ = ["CROP_SIZE", "CROP_VFOV", "SCORE_SIZE", "SPHERE_SIZE", "SPHERE_MATERIALS", "CROP_FORWARD",
           "crop_camera_fov_x", "perspective_view", "make_crop", "resize_panorama", "score_panorama",
           "sphere_mask", "render_spheres"]

#: (height, width) of the input crop.
CROP_SIZE = (192, 256)
#: Its vertical field of view, degrees.
CROP_VFOV = 60.0
#: The crop looks at the middle of the panorama image: u = 1/2 is +z in roomlight's axes.
CROP_FORWARD = (0.0, 0.0, 1.0)
#: (height, width) the panoramas are scored at.
SCORE_SIZE = (128, 256)
#: Side of the sphere renders, pixels.
SPHERE_SIZE = 128
#: The camera's distance from the unit sphere (the field's).
SPHERE_DISTANCE = 16.0
SPHERE_MATERIALS = ("diffuse", "matte", "mirror")


def crop_camera_fov_x() -> float:
    """The crop's horizontal field of view, degrees (60° vertical at 4:3: 75.18°)."""
    h, w = CROP_SIZE
    return math.degrees(2.0 * math.atan(math.tan(math.radians(CROP_VFOV / 2)) * w / h))


def _basis(forward) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    f = np.asarray(forward, np.float64)
    f = f / np.linalg.norm(f)
    right = np.cross(f, [0.0, 1.0, 0.0])
    right /= np.linalg.norm(right)
    return f, right, np.cross(right, f)


def perspective_view(pano: np.ndarray, vfov: float = CROP_VFOV, size=CROP_SIZE, forward=CROP_FORWARD) -> np.ndarray:
    """(h, w, C) a level pinhole view from the panorama's centre, bilinear (pixel centres)."""
    from roomlight.core.geometry.equirect import sample_equirect

    h, w = size
    f, right, up = _basis(forward)
    t = math.tan(math.radians(vfov / 2))
    ys = (1 - 2 * (np.arange(h) + 0.5) / h) * t
    xs = (2 * (np.arange(w) + 0.5) / w - 1) * t * w / h
    xx, yy = np.meshgrid(xs, ys)
    d = f + xx[..., None] * right + yy[..., None] * up
    x = torch.from_numpy(np.ascontiguousarray(pano, np.float32)).permute(2, 0, 1)[None]
    out = sample_equirect(x, torch.from_numpy(d).float())[0]
    return out.permute(1, 2, 0).numpy()


def make_crop(pano: np.ndarray) -> np.ndarray:
    """(192, 256, 3) float32 in [0, 1]: the protocol's input crop of a linear HDR panorama (display
    values, gamma 2.4)."""
    mapped, _ = tonemap(pano, CROP_TONEMAP)
    return np.clip(perspective_view(mapped), 0.0, 1.0).astype(np.float32)


def resize_panorama(pano: np.ndarray, size=SCORE_SIZE) -> np.ndarray:
    """An (H, W, C) panorama resized to ``size`` (antialiased bilinear)."""
    x = torch.from_numpy(np.ascontiguousarray(pano, np.float32)).permute(2, 0, 1)[None]
    y = torch.nn.functional.interpolate(x, size=tuple(size), mode="bilinear", antialias=True, align_corners=False)
    return y[0].permute(1, 2, 0).clamp_min(0).numpy()


def score_panorama(pano: np.ndarray) -> np.ndarray:
    """The panorama the spheres are rendered under: resized to 128 x 256, then E' = alpha E^(1/2.4) with
    the median of its non-zero values at 0.5."""
    return tonemap(resize_panorama(pano), SCORE_TONEMAP)[0]


def _sphere_fov() -> float:
    """The horizontal field of view that frames the unit sphere from SPHERE_DISTANCE exactly."""
    return math.degrees(2.0 * math.asin(1.0 / SPHERE_DISTANCE))


def sphere_mask(size: int = SPHERE_SIZE) -> np.ndarray:
    """(size, size) bool: the pixels whose centre ray meets the unit sphere (the render's framing)."""
    t = math.tan(math.radians(_sphere_fov() / 2))
    c = (2 * (np.arange(size) + 0.5) / size - 1) * t
    xx, yy = np.meshgrid(c, c)
    # ray o + s d, o = (0, 0, D), d = (x, y, -1)/|.|: hits when the distance from the centre to the ray < 1
    d = np.stack([xx, yy, -np.ones_like(xx)], -1)
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    o = np.array([0.0, 0.0, SPHERE_DISTANCE])
    along = -(d @ o)
    closest = np.linalg.norm(o + along[..., None] * d, axis=-1)
    return closest < 1.0


def _material(name: str) -> dict:
    if name == "diffuse":
        return {"type": "principled", "base_color": {"type": "rgb", "value": [0.8, 0.8, 0.8]}, "roughness": 0.364,
                "specular": 0.5, "metallic": 0.0}
    if name == "matte":
        return {"type": "principled", "base_color": {"type": "rgb", "value": [0.8, 0.8, 0.8]}, "roughness": 0.327,
                "metallic": 1.0}
    if name == "mirror":
        return {"type": "conductor", "material": "none", "specular_reflectance": {"type": "rgb", "value": [0.8] * 3}}
    raise ValueError(f"unknown sphere material {name!r}")


def render_spheres(pano: np.ndarray, forward=CROP_FORWARD, size: int = SPHERE_SIZE, spp: int = 64,
                   seed: int = 0) -> dict[str, np.ndarray]:
    """The three spheres under ``pano`` (an (H, 2H, 3) env map at infinity, roomlight's axes), seen along
    ``forward``: {material: (size, size, 3) float32 linear}."""
    from roomlight.core.render.camera import perspective_sensor
    from roomlight.core.render.scene import EmitterScene

    f = np.asarray(forward, np.float64) / np.linalg.norm(forward)
    origin = -SPHERE_DISTANCE * f
    sensor = perspective_sensor(origin, (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), _sphere_fov(), size, size)
    h, w = pano.shape[:2]
    out = {}
    for name in SPHERE_MATERIALS:
        es = EmitterScene("envmap", (h, w), objects={"sphere": {"type": "sphere", "radius": 1.0, "bsdf": _material(name)}},
                          sensor=sensor, integrator={"type": "path", "max_depth": 3})
        es.set_emitter(torch.from_numpy(np.ascontiguousarray(pano, np.float32)), None)
        out[name] = es.render(spp=spp, seed=seed).numpy().astype(np.float32)
    return out
