"""What a photo fit works on: the photograph at its working resolutions, the depth mesh cut into
objects, the pixels the loss sees, and the points of the frustum constraint and of the repulsion.

Everything here is in the *camera frame* (x right, y up, camera looking along -z, metres of the
depth map). :class:`SceneTransform` then places it in the room of the light: a rotation (the
camera's pitch and roll), a scale and a translation.

Two resolutions, as in the paper: the depth is meshed at ``geometry_size`` pixels (longest side)
so the objects keep their shape, and the image is rendered and compared at ``render_size``.
Neither is ever larger than the photograph.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from roomlight.errors import RoomlightError
from roomlight.core.light import similarity_parts
from roomlight.fitting.photo.camera import PhotoCamera, camera_rotation
from roomlight.fitting.photo.masks import erode, resize_nearest
from roomlight.fitting.photo.room_albedo import surface_normals
from roomlight.fitting.photo.unproject import ImageMesh, ObjectMesh, image_mesh, object_mesh, unproject

__all__ = ["SceneTransform", "FrustumSamples", "PhotoGeometry", "working_size", "resize_image", "build_geometry",
           "level_transform"]


@dataclass
class SceneTransform:
    """camera frame -> room frame: p_room = translation + scale * rotation @ p_camera.

    Attributes:
        rotation: (3, 3) camera-to-room rotation (pitch and roll; no yaw: the prior's rooms have
            every orientation about the vertical).
        scale: metres of the room per metre of the depth map.
        translation: (3,) the camera centre in the room frame.
    """

    rotation: np.ndarray
    scale: float = 1.0
    translation: np.ndarray = None

    def __post_init__(self):
        self.rotation = np.asarray(self.rotation, dtype=np.float64)
        self.translation = np.zeros(3) if self.translation is None else np.asarray(self.translation, dtype=np.float64)

    def points(self, p) -> np.ndarray:
        """(..., 3) camera-frame points -> room frame."""
        return self.translation + self.scale * np.asarray(p, dtype=np.float64) @ self.rotation.T

    def directions(self, d) -> np.ndarray:
        """(..., 3) camera-frame directions (or normals) -> room frame (not rescaled)."""
        return np.asarray(d, dtype=np.float64) @ self.rotation.T

    @property
    def forward(self) -> np.ndarray:
        return self.rotation @ np.array([0.0, 0.0, -1.0])

    @property
    def up(self) -> np.ndarray:
        return self.rotation @ np.array([0.0, 1.0, 0.0])

    def to_dict(self) -> dict:
        return {"rotation": self.rotation.round(9).tolist(), "scale": float(self.scale),
                "translation": self.translation.round(9).tolist()}

    @property
    def matrix(self) -> np.ndarray:
        """(4, 4) float64 [scale * rotation | translation]: the same map as a similarity matrix (a
        :class:`~roomlight.core.light.Light`'s frame)."""
        m = np.eye(4)
        m[:3, :3] = float(self.scale) * self.rotation
        m[:3, 3] = self.translation
        return m

    @classmethod
    def from_matrix(cls, m, what: str = "light frame") -> SceneTransform:
        """The parts of a (4, 4) similarity (see :func:`roomlight.core.light.similarity_parts`)."""
        s, r, t = similarity_parts(m, what)
        return cls(r, s, t)


@dataclass
class FrustumSamples:
    """The unmasked part of the photograph as observations of the room (camera frame).

    Attributes:
        points: (N, 3) the surfaces the pixels see, metres.
        rays: (N, 3) unit viewing directions of those pixels.
        radiance: (N, 3) their linear radiance in the photograph.
        normals: (N, 3) the surfaces' unit normals facing the camera, from the depth map.
        normal_ok: (N,) whether that normal is reliable (no depth edge next to the pixel).
    """

    points: np.ndarray
    rays: np.ndarray
    radiance: np.ndarray
    normals: np.ndarray | None = None
    normal_ok: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.points)


@dataclass
class PhotoGeometry:
    """The photograph prepared for fitting (camera frame; see the module docstring).

    Attributes:
        intrinsics: the camera at the render resolution.
        target: (Hr, Wr, 3) float32 linear photo at the render resolution, clipped to 1 (saturated).
        labels: (Hr, Wr) int32 object labels at the render resolution.
        loss_mask: (Hr, Wr) bool pixels the image loss sees: inside an object with all eight
            neighbours in the same object, so the depth mesh covers the whole pixel.
        mesh: the whole image's depth mesh at the geometry resolution.
        objects: one mesh per object label.
        frustum: observations of the room outside the objects (render resolution).
        free_points: (M, 3) points of the empty space between the camera and what it sees.
        object_points: (K, 3) points on the objects' surfaces.
        pixel_points: (Hr * Wr, 3) the point every render pixel sees (objects and room).
    """

    intrinsics: PhotoCamera
    target: np.ndarray
    labels: np.ndarray
    loss_mask: np.ndarray
    mesh: ImageMesh
    objects: list[ObjectMesh]
    frustum: FrustumSamples
    free_points: np.ndarray
    object_points: np.ndarray
    pixel_points: np.ndarray | None = None

    @property
    def labels_present(self) -> list[int]:
        return [o.label for o in self.objects]

    def contained_points(self) -> tuple[np.ndarray, np.ndarray]:
        """What a 2.5D light must enclose (camera frame): (the point every pixel sees (N, 3), so the free
        space in front of it and anything resting on it stay inside; object points (K, 3): every vertex of
        every object's mesh)."""
        objects = np.concatenate([o.vertices for o in self.objects]) if self.objects else np.zeros((0, 3))
        return self.pixel_points, objects


def working_size(height: int, width: int, longest: int) -> tuple[int, int]:
    """(h, w) with the longest side ``longest`` (never larger than the image), aspect kept."""
    s = min(1.0, longest / max(height, width))
    return max(2, int(round(height * s))), max(2, int(round(width * s)))


def resize_image(image: np.ndarray, height: int, width: int) -> np.ndarray:
    """Antialiased bilinear resampling of a linear (H, W, C) image (a plain copy at the same size)."""
    if image.shape[:2] == (height, width):
        return np.array(image, dtype=np.float32, copy=True)
    x = torch.from_numpy(np.ascontiguousarray(image, dtype=np.float32)).permute(2, 0, 1)[None]
    y = torch.nn.functional.interpolate(x, size=(height, width), mode="bilinear", antialias=True, align_corners=False)
    return y[0].permute(1, 2, 0).clamp_min(0).numpy()


def _interior(labels: np.ndarray) -> np.ndarray:
    """Pixels whose 3 x 3 neighbourhood lies in one object (pixels beyond the border count as outside)."""
    h, w = labels.shape
    p = np.pad(labels, 1, constant_values=-1)
    same = labels != 0
    for dy in (0, 1, 2):
        for dx in (0, 1, 2):
            same &= p[dy:dy + h, dx:dx + w] == labels
    return same


def build_geometry(case, config, seed: int | None = None) -> PhotoGeometry:
    """Prepare a :class:`~roomlight.fitting.photo.case.PhotoCase` for fitting under ``config``
    (:class:`~roomlight.fitting.photo.config.PhotoFitConfig`)."""
    rng = np.random.default_rng(config.seed if seed is None else seed)
    h, w = case.height, case.width
    where = case.files.get("image", "image")
    case.intrinsics.check_square_pixels(f"{where}: intrinsics")

    # --- geometry resolution: the depth mesh and the objects cut from it
    gh, gw = working_size(h, w, config.geometry_size)
    k_geo = case.intrinsics.scaled(gw, gh)
    depth_g = resize_nearest(case.depth, gh, gw)
    labels_g = resize_nearest(case.objects.labels, gh, gw)
    normals_g = resize_nearest(case.normals, gh, gw) if case.normals is not None else None
    mesh = image_mesh(depth_g, k_geo, case.depth_kind, config.edge_tolerance)
    objects = []
    skipped = []
    for label in case.objects.ids:
        try:
            objects.append(object_mesh(mesh, labels_g, label, normals_g))
        except RoomlightError:
            skipped.append(label)
    if case.objects.ids and not objects:
        raise RoomlightError(f"{case.files.get('mask', 'mask')}: no object keeps a triangle of the depth mesh at "
                             f"{gw}x{gh}; raise geometry_size or check the mask against the depth map")
    note = (f"objects {', '.join(map(str, skipped))} are too small for the {gw}x{gh} depth mesh and are left out"
            if skipped else None)
    if note and note not in case.notes:
        case.notes.append(note)

    # --- render resolution: the target, the loss mask and the frustum observations
    rh, rw = working_size(h, w, config.render_size)
    k_ren = case.intrinsics.scaled(rw, rh)
    # The photograph is a recording that saturates at 1 (paper eq. 8): an EXR's values above 1
    # count as saturated like an 8-bit photo's 255, and the censoring then reads them as "at least".
    target = np.minimum(resize_image(case.image, rh, rw), 1.0)
    labels_r = resize_nearest(case.objects.labels, rh, rw)
    kept = [o.label for o in objects]
    labels_r = np.where(np.isin(labels_r, kept), labels_r, 0).astype(np.int32)
    loss_mask = _interior(labels_r)
    if objects and not loss_mask.any():
        raise RoomlightError(f"{case.files.get('mask', 'mask')}: at the {rw}x{rh} render resolution no object has a "
                             "pixel whose neighbours all belong to it; raise render_size or use larger objects")
    depth_r = resize_nearest(case.depth, rh, rw)
    pts_r = unproject(depth_r, k_ren, case.depth_kind)
    rays_r = pts_r / np.linalg.norm(pts_r, axis=-1, keepdims=True)
    # Background pixels away from the objects' silhouettes (a pixel at the edge mixes both).
    background = erode(labels_r == 0, 1) if (labels_r == 0).any() else labels_r == 0
    idx = np.flatnonzero(background)
    if len(idx) > config.frustum_pixels:
        idx = np.sort(rng.choice(idx, config.frustum_pixels, replace=False))
    normals_r, normal_ok = surface_normals(pts_r, config.edge_tolerance)
    frustum = FrustumSamples(pts_r.reshape(-1, 3)[idx], rays_r.reshape(-1, 3)[idx], target.reshape(-1, 3)[idx],
                             normals_r.reshape(-1, 3)[idx], normal_ok.reshape(-1)[idx])

    # --- repulsion points: the objects' surfaces and the empty space in front of everything
    per = config.repulsion_points
    obj_pts = []
    for o in objects:
        take = rng.choice(len(o.vertices), min(per, len(o.vertices)), replace=False)
        obj_pts.append(o.vertices[take])
    pix = rng.integers(0, rh * rw, config.frustum_points)
    t = rng.random(config.frustum_points) * config.free_space_fraction
    # (t > 0: a point exactly at the camera centre has no direction to look the emitter up in)
    t = np.maximum(t, 1e-3)
    free = pts_r.reshape(-1, 3)[pix] * t[:, None]
    obj_pts = np.concatenate(obj_pts) if obj_pts else np.zeros((0, 3), np.float32)
    return PhotoGeometry(k_ren, target, labels_r, loss_mask, mesh, objects, frustum, free, obj_pts,
                         pts_r.reshape(-1, 3))



def level_transform(case) -> SceneTransform:
    """The camera's orientation from the case (pitch, roll), at the room's origin, unscaled."""
    return SceneTransform(camera_rotation(case.pitch_deg, case.roll_deg))
