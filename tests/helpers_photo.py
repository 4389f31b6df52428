"""Small rendered photographs with known light and materials, for the photo-fitting tests."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from roomlight.fitting.photo.camera import PhotoCamera
from roomlight.fitting.photo.synthetic import SyntheticObject, render_photo_case

#: Two spheres on the floor of the example room turned so that its window faces the camera
#: (:func:`window_room`): one near the camera on the left, one farther away near the window, in front of
#: a camera 1.5 m above the floor looking down by 20 degrees.
#: Convex objects: the depth map shows only their front, and a convex object's hidden back shadows
#: nothing that the front receives, so the photograph can determine their materials exactly.
TINY_OBJECTS = (
    (1, "sphere", 0.3, (-0.6, -1.2, -1.3), (0.70, 0.35, 0.20), 0.6, 0.0),
    (2, "sphere", 0.3, (0.6, -1.2, -2.5), (0.20, 0.45, 0.70), 0.6, 0.0),
)


def bright_wall_room(height: int = 16, wall: float = 0.9):
    """A 4 x 2.8 x 5 m box room lit mostly by its front wall (z = -3 m, radiance ``wall``), whose
    other surfaces are dim: (radiance (H, 2H, 3), radial depth (H, 2H)). The light a point receives
    depends strongly on how close it stands to the front wall."""
    import torch

    from roomlight.core.geometry.analytic import box_distance
    from roomlight.core.geometry.equirect import pixel_directions

    lo, hi = (-2.0, -1.5, -3.0), (2.0, 1.3, 2.0)
    d = pixel_directions(height, 2 * height, dtype=torch.float64)
    t = box_distance(d, lo, hi)
    p = d * t[..., None]
    rad = torch.empty(height, 2 * height, 3, dtype=torch.float64)
    rad[:] = torch.tensor([0.10, 0.09, 0.08], dtype=torch.float64)                   # side and back walls
    rad[p[..., 1] <= lo[1] + 1e-6] = torch.tensor([0.12, 0.08, 0.05], dtype=torch.float64)   # floor
    rad[p[..., 1] >= hi[1] - 1e-6] = torch.tensor([0.15, 0.15, 0.15], dtype=torch.float64)   # ceiling
    rad[p[..., 2] <= lo[2] + 1e-6] = torch.tensor([wall, wall * 0.95, wall * 0.85], dtype=torch.float64)
    return rad.float(), t.float()


def window_room(height: int = 16):
    """The example room turned by a quarter turn about the vertical, so that its window, on the
    +x wall, lies ahead of a camera looking along -z: (radiance (H, 2H, 3), radial depth (H, 2H))."""
    import torch

    from roomlight.core.examples import example_room

    rad, depth = example_room(height)
    shift = -(2 * height) // 4   # u -> u - 1/4: the direction u = 1/4 (+x) moves to u = 0 (-z)
    return torch.roll(rad, shift, dims=1), torch.roll(depth, shift, dims=1)


def tiny_objects(objects=TINY_OBJECTS) -> list[SyntheticObject]:
    from roomlight.fitting.scene.shapes import builtin_shape

    out = []
    for label, shape, radius, centre, albedo, rough, metal in objects:
        v, f = builtin_shape(shape)
        out.append(SyntheticObject(label, v.astype(np.float64) * radius + np.asarray(centre), f.astype(np.int64),
                                   albedo, rough, metal))
    return out


def make_tiny_photo(folder: Path, radiance, depth, size=(48, 64), fov=70.0, pitch=-20.0, spp=128, objects=None,
                    origin=(0.0, 0.0, 0.0), key=0.35):
    """A photo case of ``objects`` (default: :data:`TINY_OBJECTS`) under the room (radiance, depth)."""
    h, w = size
    return render_photo_case(folder, radiance, depth, objects or tiny_objects(), PhotoCamera.from_fov(fov, w, h),
                             origin=origin, pitch_deg=pitch, spp=spp, seed=5, depth_kind="z", object_key=key)
