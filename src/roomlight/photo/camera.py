"""The pinhole camera of a photograph: intrinsics in pixels, orientation, and their conversions.

Pixel coordinates are continuous, with (0, 0) at the top-left *corner* of the image: pixel
(row i, column j) covers [j, j + 1) x [i, i + 1) and has its centre at (j + 0.5, i + 0.5). A
principal point in the middle of a W x H image is therefore (W / 2, H / 2). (This is COLMAP's
convention; OpenCV puts the first pixel's centre at 0, i.e. its cx is ours minus 0.5.)

Camera frame: x to the right of the image, y up, z towards the viewer, so the camera looks
along -z; this is roomlight's capture frame when the camera is level (pitch = roll = 0). A pixel
centre (u, v) sees the direction ((u - cx) / fx, -(v - cy) / fy, -1).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from roomlight.errors import RoomlightError

__all__ = ["Intrinsics", "camera_rotation", "SQUARE_PIXEL_TOLERANCE"]

#: Largest relative difference between fx and fy that the renderer accepts (Mitsuba's pinhole
#: camera has square pixels); 1 % moves the image's top and bottom rows by at most 0.5 % of its height.
SQUARE_PIXEL_TOLERANCE = 0.01


@dataclass(frozen=True)
class Intrinsics:
    """Pinhole intrinsics of a width x height image, in pixels (see the module docstring).

    Attributes:
        fx, fy: focal lengths in pixels (> 0).
        cx, cy: principal point in pixels, (0, 0) at the image's top-left corner.
        width, height: the image size these values refer to.
    """

    fx: float
    fy: float
    cx: float
    cy: float
    width: int
    height: int

    def __post_init__(self):
        values = (self.fx, self.fy, self.cx, self.cy)
        if not all(math.isfinite(v) for v in values) or self.fx <= 0 or self.fy <= 0:
            raise RoomlightError(f"intrinsics: fx, fy must be positive and cx, cy finite, got {values}")
        if self.width <= 0 or self.height <= 0:
            raise RoomlightError(f"intrinsics: image size must be positive, got {self.width}x{self.height}")

    # ------------------------------------------------------------------ constructors
    @classmethod
    def from_fov(cls, fov_deg: float, width: int, height: int) -> "Intrinsics":
        """Square pixels, principal point at the centre, ``fov_deg`` the *horizontal* field of view."""
        if not 0.0 < fov_deg < 180.0:
            raise RoomlightError(f"intrinsics: the horizontal field of view must be in (0, 180) degrees, got {fov_deg}")
        f = width / (2.0 * math.tan(math.radians(fov_deg) / 2.0))
        return cls(f, f, width / 2.0, height / 2.0, width, height)

    @classmethod
    def parse(cls, text: str, width: int, height: int) -> "Intrinsics":
        """``fx,fy,cx,cy`` (pixels) for a width x height image."""
        parts = [p.strip() for p in str(text).split(",")]
        try:
            if len(parts) != 4:
                raise ValueError
            fx, fy, cx, cy = (float(p) for p in parts)
        except ValueError:
            raise RoomlightError(f"intrinsics {text!r}: expected four numbers fx,fy,cx,cy in pixels") from None
        return cls(fx, fy, cx, cy, width, height)

    # ------------------------------------------------------------------ derived values
    @property
    def fov_deg(self) -> float:
        """Horizontal field of view in degrees (of a centred principal point)."""
        return math.degrees(2.0 * math.atan(self.width / (2.0 * self.fx)))

    def scaled(self, width: int, height: int) -> "Intrinsics":
        """The same camera for the image resampled to width x height (continuous coordinates scale)."""
        sx, sy = width / self.width, height / self.height
        return Intrinsics(self.fx * sx, self.fy * sy, self.cx * sx, self.cy * sy, width, height)

    def pixel_rays(self) -> np.ndarray:
        """(H, W, 3) float64 camera-frame directions ((u - cx)/fx, -(v - cy)/fy, -1) through the pixel
        centres; not normalised: a z-depth Z multiplies them directly."""
        u = np.arange(self.width, dtype=np.float64) + 0.5
        v = np.arange(self.height, dtype=np.float64) + 0.5
        x = (u - self.cx) / self.fx
        y = -(v - self.cy) / self.fy
        xx, yy = np.meshgrid(x, y)
        return np.stack([xx, yy, -np.ones_like(xx)], -1)

    def check_square_pixels(self, where: str = "intrinsics") -> None:
        """Refuse fx and fy further apart than :data:`SQUARE_PIXEL_TOLERANCE` (the renderer's camera
        has square pixels)."""
        if abs(self.fx - self.fy) > SQUARE_PIXEL_TOLERANCE * max(self.fx, self.fy):
            raise RoomlightError(
                f"{where}: fx = {self.fx:.6g} and fy = {self.fy:.6g} differ by more than "
                f"{SQUARE_PIXEL_TOLERANCE:.0%}; the renderer needs square pixels (resample the image so that fx = fy)")

    def to_dict(self) -> dict:
        return {"fx": self.fx, "fy": self.fy, "cx": self.cx, "cy": self.cy}


def camera_rotation(pitch_deg: float = 0.0, roll_deg: float = 0.0) -> np.ndarray:
    """(3, 3) rotation from the camera frame to the room frame (y up).

    ``roll`` turns the camera about its viewing axis (positive: counter-clockwise as seen from
    behind the camera, so the image content turns clockwise), then ``pitch`` tilts it about the
    room's x axis (positive: looking up). Level camera: the identity.
    """
    p, r = math.radians(pitch_deg), math.radians(roll_deg)
    rx = np.array([[1, 0, 0], [0, math.cos(p), -math.sin(p)], [0, math.sin(p), math.cos(p)]])
    rz = np.array([[math.cos(r), -math.sin(r), 0], [math.sin(r), math.cos(r), 0], [0, 0, 1]])
    return rx @ rz
