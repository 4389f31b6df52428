"""Training views for the view encoder, cut from panoramas: no rendering needed.

A crop is a pinhole view from the panorama's capture point: horizontal field of view, aspect
(width / height), pitch and roll (:func:`roomlight.fitting.photo.camera.camera_rotation`) and yaw (a turn
about the vertical applied after them; see :func:`crop_rotation`). Its pixels look along
the same directions as :func:`roomlight.core.geometry.projection.perspective_directions` with the
camera's forward and up vectors, and carry the panorama's radiance and the camera-frame point at
the panorama's radial depth, which is what a photograph with a depth map gives
(:func:`roomlight.fitting.photo.unproject.unproject`).

What a photograph has that a crop has not is simulated on the crop:

- an exposure: the crop is scaled so its log-average luminance is a random grey level, then
  clipped at 1 as a camera would (lamps and windows saturate);
- objects in front of the room: random ellipses are marked invalid, as the fit leaves a photo's
  objects out of its view.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import torch

from roomlight.core.color import LOG_EPS, luminance_torch
from roomlight.core.geometry.equirect import sample_equirect
from roomlight.fitting.photo.camera import PhotoCamera, camera_rotation

__all__ = ["CropSpec", "crop_rotation", "cut_view", "random_crop_spec", "occluder_mask", "expose"]


@dataclass(frozen=True)
class CropSpec:
    """One perspective view from the capture point (angles in degrees)."""

    fov_deg: float
    height: int
    width: int
    pitch_deg: float = 0.0
    roll_deg: float = 0.0
    yaw_deg: float = 0.0

    @property
    def intrinsics(self) -> PhotoCamera:
        return PhotoCamera.from_fov(self.fov_deg, self.width, self.height)


def crop_rotation(spec: CropSpec) -> np.ndarray:
    """(3, 3) camera -> room rotation: roll, then pitch, then yaw about +y (counter-clockwise
    seen from above, so yaw 90 degrees turns a camera looking along -z to look along -x)."""
    a = math.radians(spec.yaw_deg)
    ry = np.array([[math.cos(a), 0.0, math.sin(a)], [0.0, 1.0, 0.0], [-math.sin(a), 0.0, math.cos(a)]])
    return ry @ camera_rotation(spec.pitch_deg, spec.roll_deg)


def cut_view(radiance: torch.Tensor, depth: torch.Tensor, spec: CropSpec) -> tuple[torch.Tensor, torch.Tensor]:
    """Cut the view ``spec`` out of a panorama.

    Args:
        radiance: (3, H, W) linear radiance panorama.
        depth: (1, H, W) radial depth panorama, metres.
    Returns:
        (image (h, w, 3) linear radiance, points (h, w, 3) camera-frame points in metres).
    """
    rays = torch.from_numpy(spec.intrinsics.pixel_rays())
    rays = rays / rays.norm(dim=-1, keepdim=True)                       # camera frame, unit
    dirs = rays @ torch.from_numpy(crop_rotation(spec)).T               # room frame
    pano = torch.cat([radiance, torch.log(depth)], dim=0)[None].double()
    values = sample_equirect(pano, dirs)[0].permute(1, 2, 0)             # (h, w, 4)
    image = values[..., :3].clamp_min(0.0)
    points = rays * values[..., 3:].exp()
    return image.float(), points.float()


def random_crop_spec(rng: np.random.Generator, pano_width: int, fov=(40.0, 100.0), pitch=25.0, roll=5.0,
                     aspect=(1.0, 1.8), yaw: bool = True, samples_per_cell: float | None = None) -> CropSpec:
    """A random view: fov uniform in ``fov``, pitch uniform in ±``pitch``, roll in ±``roll``, aspect
    (landscape) uniform in ``aspect``, yaw uniform (or 0), at the resolution that
    :func:`~roomlight.core.geometry.lift.lift_resolution` gives for ``pano_width``."""
    from roomlight.core.geometry.lift import SAMPLES_PER_CELL, lift_resolution

    f = float(rng.uniform(*fov))
    asp = float(rng.uniform(*aspect))
    h, w = lift_resolution(f, asp, pano_width, samples_per_cell or SAMPLES_PER_CELL)
    return CropSpec(f, h, w, float(rng.uniform(-pitch, pitch)), float(rng.uniform(-roll, roll)),
                    float(rng.uniform(0.0, 360.0)) if yaw else 0.0)


def occluder_mask(rng: np.random.Generator, height: int, width: int, max_count: int = 3,
                  max_share: float = 0.35) -> np.ndarray:
    """(h, w) bool: True where the view shows the room, False under up to ``max_count`` random
    ellipses (objects) covering together at most about ``max_share`` of the view."""
    valid = np.ones((height, width), dtype=bool)
    yy, xx = np.mgrid[0:height, 0:width]
    for _ in range(int(rng.integers(0, max_count + 1))):
        area = rng.uniform(0.01, max_share / max(1, max_count)) * height * width
        ratio = rng.uniform(0.5, 2.0)
        ry = math.sqrt(area / math.pi / ratio)
        rx = ry * ratio
        cy = rng.uniform(0.4, 1.0) * height            # objects stand low in a view more often
        cx = rng.uniform(0.0, 1.0) * width
        valid &= ((yy - cy) / ry) ** 2 + ((xx - cx) / rx) ** 2 > 1.0
    return valid


def expose(image: torch.Tensor, log_key: float) -> tuple[torch.Tensor, float]:
    """Scale a linear (h, w, 3) view so its log-average luminance is ``exp(log_key)``, then clip at
    1 (a camera's saturation). Returns the exposed image and the log of the factor applied."""
    y = luminance_torch(image.double().permute(2, 0, 1))
    log_avg = float(torch.log(y + LOG_EPS).mean())
    a = log_key - log_avg
    return (image * math.exp(a)).clamp(max=1.0), a
