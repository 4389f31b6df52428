"""The pinhole camera of a photograph: intrinsics in pixels, its pose, and their conversions.

Pixel coordinates are continuous, with (0, 0) at the top-left *corner* of the image: pixel
(row i, column j) covers [j, j + 1) x [i, i + 1) and has its centre at (j + 0.5, i + 0.5). A
principal point in the middle of a W x H image is therefore (W / 2, H / 2). (This is COLMAP's
convention; OpenCV puts the first pixel's centre at 0, i.e. its cx is ours minus 0.5.)

Camera frame: x to the right of the image, y up, z towards the viewer, so the camera looks
along -z; this is roomlight's capture frame when the camera is level (pitch = roll = 0). A
camera-frame point q is seen at

    x = cx + fx * q_x / (-q_z),      y = cy - fy * q_y / (-q_z)

(pixels, x to the right, y downwards), so a pixel centre (u, v) sees the direction
((u - cx) / fx, -(v - cy) / fy, -1). The **z-depth** of a point is ``-q_z`` (metres along the
optical axis); its radial depth is ``|q|``.

The pose ``camera_to_world`` (rigid, metres) places the camera in a world: a world point p has
camera coordinates q = R^T (p - o) (R, o: its rotation and position). A photograph alone
(``roomlight fit-photo``) has no world: its camera keeps the identity pose and everything is
measured in its camera frame. The photo benchmark's cameras carry their pose in the room.

Rays are generated here rather than by Mitsuba's ``perspective`` sensor so that fx != fy and an
off-centre principal point are honoured exactly, and so that depth, masks and renders use the
very same rays.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from roomlight.errors import RoomlightError

__all__ = ["PhotoCamera", "camera_rotation", "SQUARE_PIXEL_TOLERANCE"]

#: Largest relative difference between fx and fy that the renderer accepts (Mitsuba's pinhole
#: camera has square pixels); 1 % moves the image's top and bottom rows by at most 0.5 % of its height.
SQUARE_PIXEL_TOLERANCE = 0.01

_IDENTITY = tuple(tuple(float(v) for v in row) for row in np.eye(4))


def _rigid(m, what: str) -> np.ndarray:
    m = np.asarray(m, np.float64)
    if m.shape != (4, 4) or not np.isfinite(m).all():
        raise RoomlightError(f"{what}: expected a finite 4x4 matrix, got shape {m.shape}")
    r = m[:3, :3]
    if not np.allclose(r.T @ r, np.eye(3), atol=1e-5) or np.linalg.det(r) < 0 or not np.allclose(m[3], [0, 0, 0, 1]):
        raise RoomlightError(f"{what}: not a rigid transform (rotation + translation, last row 0 0 0 1)")
    return m


@dataclass(frozen=True)
class PhotoCamera:
    """A pinhole camera (see the module docstring for the frames).

    Attributes:
        width, height: image size in pixels.
        fx, fy: focal lengths in pixels (> 0); cx, cy: principal point in pixels, (0, 0) at the
            image's top-left corner.
        camera_to_world: (4, 4) rigid transform, camera frame -> world frame (metres), stored as
            nested tuples; the identity for a photograph's own camera.
    """

    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float
    camera_to_world: tuple = _IDENTITY

    def __post_init__(self):
        values = (self.fx, self.fy, self.cx, self.cy)
        if not all(math.isfinite(v) for v in values) or self.fx <= 0 or self.fy <= 0:
            raise RoomlightError(f"intrinsics: fx, fy must be positive and cx, cy finite, got {values}")
        if self.width <= 0 or self.height <= 0:
            raise RoomlightError(f"camera: image size must be positive, got {self.width}x{self.height}")
        m = _rigid(self.camera_to_world, "camera_to_world")
        object.__setattr__(self, "camera_to_world", tuple(tuple(float(v) for v in row) for row in m))

    # -- construction -------------------------------------------------------------------------
    @classmethod
    def from_fov(cls, fov_deg: float, width: int, height: int) -> PhotoCamera:
        """Square pixels, principal point at the centre, ``fov_deg`` the *horizontal* field of view;
        identity pose."""
        if not 0.0 < fov_deg < 180.0:
            raise RoomlightError(f"intrinsics: the horizontal field of view must be in (0, 180) degrees, got {fov_deg}")
        f = width / (2.0 * math.tan(math.radians(fov_deg) / 2.0))
        return cls(width, height, f, f, width / 2.0, height / 2.0)

    @classmethod
    def parse(cls, text: str, width: int, height: int) -> PhotoCamera:
        """``fx,fy,cx,cy`` (pixels) for a width x height image; identity pose."""
        parts = [p.strip() for p in str(text).split(",")]
        try:
            if len(parts) != 4:
                raise ValueError
            fx, fy, cx, cy = (float(p) for p in parts)
        except ValueError:
            raise RoomlightError(f"intrinsics {text!r}: expected four numbers fx,fy,cx,cy in pixels") from None
        return cls(width, height, fx, fy, cx, cy)

    @classmethod
    def look_at(cls, origin, target, fov_deg: float, width: int, height: int, up=(0.0, 1.0, 0.0)) -> PhotoCamera:
        """A camera at ``origin`` looking at ``target`` with horizontal field of view ``fov_deg``,
        square pixels and the principal point at the image centre."""
        o = np.asarray(origin, np.float64)
        f = np.asarray(target, np.float64) - o
        if np.linalg.norm(f) < 1e-9:
            raise RoomlightError("camera: origin and target coincide")
        f /= np.linalg.norm(f)
        r = np.cross(f, np.asarray(up, np.float64))
        if np.linalg.norm(r) < 1e-9:
            raise RoomlightError("camera: the view direction is parallel to up")
        r /= np.linalg.norm(r)
        u = np.cross(r, f)
        m = np.eye(4)
        m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = r, u, -f, o
        return replace(cls.from_fov(fov_deg, int(width), int(height)), camera_to_world=m)

    @classmethod
    def from_dict(cls, d: dict, where: str = "camera.json") -> PhotoCamera:
        """Read the ``camera.json`` mapping (see :meth:`to_dict`)."""
        try:
            return cls(int(d["width"]), int(d["height"]), float(d["fx"]), float(d["fy"]), float(d["cx"]),
                       float(d["cy"]), np.asarray(d["camera_to_world"], np.float64))
        except KeyError as exc:
            raise RoomlightError(f"{where}: missing {exc.args[0]!r}") from None
        except (TypeError, ValueError) as exc:
            raise RoomlightError(f"{where}: {exc}") from None

    def to_dict(self) -> dict:
        """``camera.json`` fields: size, intrinsics (pixels), ``camera_to_world`` (4 x 4, row-major)."""
        return {"width": self.width, "height": self.height, "fx": self.fx, "fy": self.fy, "cx": self.cx,
                "cy": self.cy, "camera_to_world": [list(r) for r in self.camera_to_world]}

    def intrinsics_dict(self) -> dict:
        """The intrinsics alone, ``{fx, fy, cx, cy}`` in pixels (what photo records and ``camera.json`` of a
        photo case hold)."""
        return {"fx": self.fx, "fy": self.fy, "cx": self.cx, "cy": self.cy}

    # -- intrinsics -----------------------------------------------------------------------------
    @property
    def fov_x(self) -> float:
        """Horizontal field of view, degrees (for a centred principal point)."""
        return math.degrees(2.0 * math.atan(0.5 * self.width / self.fx))

    def scaled(self, width: int, height: int) -> PhotoCamera:
        """The same camera for the image resampled to width x height (continuous coordinates scale)."""
        sx, sy = width / self.width, height / self.height
        return replace(self, width=width, height=height, fx=self.fx * sx, fy=self.fy * sy, cx=self.cx * sx,
                       cy=self.cy * sy)

    def check_square_pixels(self, where: str = "intrinsics") -> None:
        """Refuse fx and fy further apart than :data:`SQUARE_PIXEL_TOLERANCE` (the renderer's camera
        has square pixels)."""
        if abs(self.fx - self.fy) > SQUARE_PIXEL_TOLERANCE * max(self.fx, self.fy):
            raise RoomlightError(
                f"{where}: fx = {self.fx:.6g} and fy = {self.fy:.6g} differ by more than "
                f"{SQUARE_PIXEL_TOLERANCE:.0%}; the renderer needs square pixels (resample the image so that fx = fy)")

    def pixel_rays(self) -> np.ndarray:
        """(H, W, 3) float64 camera-frame directions ((u - cx)/fx, -(v - cy)/fy, -1) through the pixel
        centres; not normalised: a z-depth Z multiplies them directly."""
        u = np.arange(self.width, dtype=np.float64) + 0.5
        v = np.arange(self.height, dtype=np.float64) + 0.5
        x = (u - self.cx) / self.fx
        y = -(v - self.cy) / self.fy
        xx, yy = np.meshgrid(x, y)
        return np.stack([xx, yy, -np.ones_like(xx)], -1)

    # -- pose -----------------------------------------------------------------------------------
    @property
    def matrix(self) -> np.ndarray:
        """(4, 4) camera-to-world."""
        return np.asarray(self.camera_to_world, np.float64)

    @property
    def origin(self) -> np.ndarray:
        """(3,) camera position, world frame."""
        return self.matrix[:3, 3].copy()

    @property
    def forward(self) -> np.ndarray:
        """(3,) unit optical axis (world frame)."""
        return -self.matrix[:3, 2]

    def orientation_deg(self) -> tuple[float, float, float]:
        """(yaw, pitch, roll) in degrees with camera-to-world rotation R_y(yaw) R_x(pitch) R_z(roll):
        ``pitch`` > 0 looks up, ``roll`` turns the camera counter-clockwise about its viewing axis
        (as seen from behind it). ``pitch`` and ``roll`` are the ``pitch_deg`` and ``roll_deg`` of a
        photo case's ``camera.json`` (the camera's tilt relative to the room; the yaw is unknown to a
        method and irrelevant to it)."""
        r = self.matrix[:3, :3]
        yaw = math.atan2(r[0, 2], r[2, 2])
        c, s = math.cos(yaw), math.sin(yaw)
        level = np.array([[c, 0.0, -s], [0.0, 1.0, 0.0], [s, 0.0, c]]) @ r  # R_y(-yaw) R = R_x R_z
        pitch = math.atan2(-level[1, 2], level[2, 2])
        roll = math.atan2(-level[0, 1], level[0, 0])
        return math.degrees(yaw), math.degrees(pitch), math.degrees(roll)

    def transformed(self, world_to_frame: np.ndarray) -> PhotoCamera:
        """The same camera expressed in another frame (``world_to_frame``: (4, 4) rigid)."""
        return replace(self, camera_to_world=_rigid(world_to_frame, "frame transform") @ self.matrix)

    # -- rays and projection (world frame) ------------------------------------------------------
    def directions(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """(N, 3) unit world directions through film points (x, y) in pixels (float64)."""
        q = np.stack([(np.asarray(x, np.float64) - self.cx) / self.fx,
                      -(np.asarray(y, np.float64) - self.cy) / self.fy,
                      -np.ones(np.shape(x))], -1)
        d = q @ self.matrix[:3, :3].T
        return d / np.linalg.norm(d, axis=-1, keepdims=True)

    def pixel_centres(self) -> tuple[np.ndarray, np.ndarray]:
        """Film coordinates (x, y) of every pixel centre, (H * W,) each, row-major."""
        jj, ii = np.meshgrid(np.arange(self.width) + 0.5, np.arange(self.height) + 0.5)
        return jj.ravel(), ii.ravel()

    def project(self, points) -> tuple[np.ndarray, np.ndarray]:
        """World points (N, 3) -> (pixel coordinates (N, 2) as (x, y), z-depth (N,) metres)."""
        p = np.asarray(points, np.float64).reshape(-1, 3)
        m = self.matrix
        q = (p - m[:3, 3]) @ m[:3, :3]
        z = -q[:, 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            xy = np.stack([self.cx + self.fx * q[:, 0] / z, self.cy - self.fy * q[:, 1] / z], -1)
        return xy, z

    def sphere_pixels(self, centre, radius: float) -> np.ndarray:
        """(H, W) bool: pixels whose centre ray hits the sphere (an analytic test, no occlusion)."""
        d = self.directions(*self.pixel_centres())
        oc = self.origin - np.asarray(centre, np.float64)
        b = d @ oc
        disc = b * b - (oc @ oc - radius * radius)
        return (disc >= 0).reshape(self.height, self.width) & (-b + np.sqrt(np.maximum(disc, 0)) > 0).reshape(
            self.height, self.width)


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
