"""Tangent-plane (gnomonic) views of a panorama: the 12 icosahedron views the depth estimator sees.

The view centres are the 12 vertices of a regular icosahedron, (0, +-1, +-phi), (+-1, +-phi, 0),
(+-phi, 0, +-1) normalised (phi the golden ratio), in the panorama frame (y up): four on the
horizon, two at each of +-31.7 deg and two at each of +-58.3 deg elevation.
Neighbouring centres are 63.4 deg apart and every direction is within 37.4 deg of a centre, so
square 90 deg views overlap generously; each pole lies 31.7 deg off the axis of two views. No
view looks straight up or down, so every view can keep the world's up as its up vector.

Views are cut with :func:`roomlight.core.geometry.projection.panorama_to_perspective` and pasted back
with :func:`~roomlight.core.geometry.projection.perspective_to_panorama` (the project's camera
convention: horizontal field of view, image y down, right = forward x up).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import torch

from roomlight.core.geometry.projection import panorama_to_perspective, perspective_directions, perspective_to_panorama

__all__ = ["View", "icosahedron_directions", "cut_views", "view_plane_coordinates", "view_to_panorama",
           "default_view_size"]

UP = (0.0, 1.0, 0.0)


def icosahedron_directions() -> np.ndarray:
    """(12, 3) float64 unit vectors: the vertices of a regular icosahedron (see the module docstring)."""
    p = (1.0 + math.sqrt(5.0)) / 2.0
    v = []
    for a in (-1.0, 1.0):
        for b in (-1.0, 1.0):
            v += [(0.0, a, b * p), (a, b * p, 0.0), (b * p, 0.0, a)]
    v = np.asarray(v, np.float64)
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def default_view_size(pano_height: int, fov_deg: float = 90.0) -> int:
    """Square view size whose centre pixels are half a panorama pixel wide (2x oversampling), 64..512."""
    n = 2.0 * math.tan(math.radians(fov_deg) / 2.0) / (math.pi / pano_height) * 2.0
    return int(min(512, max(64, round(n))))


@dataclass
class View:
    """One perspective view of the panorama, as a depth estimator receives it.

    Attributes:
        index: position in the list of views (0..11).
        image: (h, w, 3) float32 display values in [0, 1] (tone mapped, gamma 2.2).
        directions: (h, w, 3) float32 unit directions of the pixel centres, panorama frame (y up).
        forward, up: the view's axis and up vector (panorama frame).
        fov_deg: horizontal (= vertical, square views) field of view in degrees.
    """

    index: int
    image: np.ndarray
    directions: np.ndarray
    forward: tuple
    up: tuple
    fov_deg: float

    @property
    def size(self) -> tuple[int, int]:
        return int(self.image.shape[0]), int(self.image.shape[1])

    def cos_to_axis(self) -> np.ndarray:
        """(h, w) cosine between each pixel's ray and the axis: planar z-depth = distance x cos."""
        return np.asarray(self.directions, np.float64) @ np.asarray(self.forward, np.float64)


def view_plane_coordinates(height: int, width: int) -> tuple[np.ndarray, np.ndarray]:
    """(h, w) normalised image-plane coordinates x (right) and y (down) of the pixel centres, in (-1, 1)."""
    x = (np.arange(width) + 0.5) / width * 2.0 - 1.0
    y = (np.arange(height) + 0.5) / height * 2.0 - 1.0
    yy, xx = np.meshgrid(y, x, indexing="ij")
    return xx, yy


def cut_views(display: np.ndarray, size: int, fov_deg: float = 90.0,
              centres: np.ndarray | None = None) -> list[View]:
    """Perspective views of a display-referred panorama.

    Args:
        display: (H, W, 3) display values (see :class:`roomlight.datagen.prepare.tonemap.DisplayMap`).
        size: square view size in pixels.
        fov_deg: field of view of each view.
        centres: (K, 3) view axes; default :func:`icosahedron_directions`.
    Returns:
        K views with images clipped to [0, 1].
    """
    centres = icosahedron_directions() if centres is None else np.asarray(centres, np.float64)
    pano = torch.from_numpy(np.ascontiguousarray(np.asarray(display, np.float32).transpose(2, 0, 1)))[None]
    views = []
    for k, f in enumerate(centres):
        fwd = tuple(float(c) for c in f)
        img = panorama_to_perspective(pano, size, size, fov_deg, fwd, UP)[0].permute(1, 2, 0).numpy()
        dirs = perspective_directions(size, size, fov_deg, fwd, UP, dtype=torch.float32).numpy()
        views.append(View(k, np.clip(img, 0.0, 1.0).astype(np.float32), dirs, fwd, UP, float(fov_deg)))
    return views


def view_to_panorama(values: np.ndarray, view: View, height: int) -> tuple[np.ndarray, np.ndarray]:
    """Paste (h, w, C) per-pixel values of a view back onto an (height, 2 height) panorama.

    Returns:
        (H, W, C) float64 values bilinearly interpolated from the view where a pixel's direction
        falls inside it (0 elsewhere), and the (H, W) bool mask of those pixels.
    """
    t = torch.from_numpy(np.ascontiguousarray(np.asarray(values, np.float64).transpose(2, 0, 1)))[None]
    out, mask = perspective_to_panorama(t, height, view.fov_deg, view.forward, view.up)
    return out[0].permute(1, 2, 0).numpy(), mask.numpy()
