"""The photo camera: a pinhole with intrinsics (fx, fy, cx, cy) and a camera-to-world pose.

Camera frame (the project's view convention): x right, y up, the camera looks along -z. A
world point p maps to camera coordinates q = R^T (p - o) (R, o: rotation and position of
``camera_to_world``) and to pixel coordinates

    x = cx + fx * q_x / (-q_z),      y = cy - fy * q_y / (-q_z),

x to the right and y downwards, in pixels; pixel (i, j) covers x in [j, j + 1), y in [i, i + 1),
so its centre is (j + 0.5, i + 0.5) and ``cx = W / 2`` puts the principal point at the image
centre. The **z-depth** of a point is ``-q_z`` (metres along the optical axis); the radial
depth is ``|q|``.

Rays are generated here rather than by Mitsuba's ``perspective`` sensor so that fx != fy and an
off-centre principal point are honoured exactly, and so that depth, masks and renders use the
very same rays.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from roomlight.errors import RoomlightError

__all__ = ["PhotoCamera"]


def _rigid(m: np.ndarray, what: str) -> np.ndarray:
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
        fx, fy: focal lengths in pixels; cx, cy: principal point in pixels (from the top-left corner).
        camera_to_world: (4, 4) rigid transform, camera frame -> world frame (metres).
    """

    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float
    camera_to_world: tuple

    def __post_init__(self):
        if self.width <= 0 or self.height <= 0:
            raise RoomlightError(f"camera: image size must be positive, got {self.width}x{self.height}")
        if not (self.fx > 0 and self.fy > 0):
            raise RoomlightError(f"camera: focal lengths must be positive, got fx={self.fx}, fy={self.fy}")
        m = _rigid(self.camera_to_world, "camera_to_world")
        object.__setattr__(self, "camera_to_world", tuple(tuple(float(v) for v in row) for row in m))

    # -- construction -------------------------------------------------------------------------
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
        fx = 0.5 * width / math.tan(math.radians(fov_deg) / 2.0)
        return cls(int(width), int(height), fx, fx, 0.5 * width, 0.5 * height, m)

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

    # -- geometry -----------------------------------------------------------------------------
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

    @property
    def fov_x(self) -> float:
        """Horizontal field of view, degrees (for a centred principal point)."""
        return math.degrees(2.0 * math.atan(0.5 * self.width / self.fx))

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
        m = _rigid(world_to_frame, "frame transform") @ self.matrix
        return PhotoCamera(self.width, self.height, self.fx, self.fy, self.cx, self.cy, m)

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
