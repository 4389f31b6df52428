"""From a depth map to geometry: unprojected points, the triangulated image mesh, object meshes.

Every pixel centre becomes a vertex at its depth along its camera ray (see
:mod:`roomlight.fitting.photo.camera` for the frame). Neighbouring pixels form a quad grid split into
two triangles; a triangle is dropped where the depth jumps (its largest radial distance exceeds
its smallest by more than ``edge_tolerance``), which is where the surface behind an occluding
edge would otherwise be welded to the edge. Triangles face the camera, so Mitsuba's one-sided
BSDFs shade the side the photograph shows.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from roomlight.errors import RoomlightError
from roomlight.fitting.photo.camera import PhotoCamera

__all__ = ["DEPTH_KINDS", "unproject", "radial_distance", "ImageMesh", "image_mesh", "ObjectMesh", "object_mesh",
           "vertex_normals"]

#: ``z``: distance along the optical axis (what depth sensors and monocular estimators such as
#: MoGe give); ``radial``: distance from the camera centre (what roomlight's panoramas store).
DEPTH_KINDS = ("z", "radial")


def unproject(depth: np.ndarray, intrinsics: PhotoCamera, kind: str = "z") -> np.ndarray:
    """Camera-frame points of every pixel centre.

    Args:
        depth: (H, W) metres, z-depth or radial distance (``kind``), > 0.
        intrinsics: of an H x W image.
    Returns:
        (H, W, 3) float64 points in metres (x right, y up, camera looking along -z).
    """
    if kind not in DEPTH_KINDS:
        raise RoomlightError(f"depth kind {kind!r}: expected one of {', '.join(DEPTH_KINDS)}")
    d = np.asarray(depth, dtype=np.float64)
    if d.shape != (intrinsics.height, intrinsics.width):
        raise RoomlightError(f"unproject: depth is {d.shape[1]}x{d.shape[0]} but the intrinsics are for a "
                             f"{intrinsics.width}x{intrinsics.height} image")
    rays = intrinsics.pixel_rays()
    if kind == "radial":
        rays = rays / np.linalg.norm(rays, axis=-1, keepdims=True)
    return rays * d[..., None]


def radial_distance(depth: np.ndarray, intrinsics: PhotoCamera, kind: str = "z") -> np.ndarray:
    """(H, W) distance of each pixel's point from the camera centre, metres."""
    return np.linalg.norm(unproject(depth, intrinsics, kind), axis=-1)


def _grid_triangles(h: int, w: int) -> np.ndarray:
    """(2 (H-1)(W-1), 3) vertex indices i W + j of the pixel grid, facing the camera."""
    idx = np.arange(h * w).reshape(h, w)
    a, b = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel()
    c, d = idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    # (a, c, b): down x right in the camera frame (y up) is +z, towards the camera.
    return np.concatenate([np.stack([a, c, b], 1), np.stack([b, c, d], 1)])


@dataclass
class ImageMesh:
    """The triangulated depth of a whole image.

    Attributes:
        points: (H, W, 3) camera-frame vertex positions (metres), one per pixel centre.
        faces: (F, 3) int64 indices into ``points.reshape(-1, 3)``; only the kept triangles.
        shape: (H, W).
    """

    points: np.ndarray
    faces: np.ndarray

    @property
    def shape(self) -> tuple[int, int]:
        return self.points.shape[:2]

    @property
    def vertices(self) -> np.ndarray:
        return self.points.reshape(-1, 3)


def image_mesh(depth: np.ndarray, intrinsics: PhotoCamera, kind: str = "z", edge_tolerance: float = 0.05) -> ImageMesh:
    """Triangulate the unprojected depth, dropping triangles across depth discontinuities.

    A triangle is kept when max(r) <= (1 + edge_tolerance) min(r) over its three vertices' radial
    distances r. The test is scale-free; a plane seen at an angle alpha from its normal changes
    its distance by about tan(alpha) x (pixel angle) per pixel, e.g. 2.5 % at 80 degrees in a
    256-pixel-wide image of 65 degrees, so only much steeper jumps are cut at the default 5 %.
    """
    pts = unproject(depth, intrinsics, kind)
    h, w = pts.shape[:2]
    if h < 2 or w < 2:
        raise RoomlightError(f"image mesh: the depth map must be at least 2x2 pixels, got {w}x{h}")
    faces = _grid_triangles(h, w)
    r = np.linalg.norm(pts, axis=-1).ravel()[faces]
    keep = r.max(1) <= (1.0 + edge_tolerance) * r.min(1)
    return ImageMesh(pts, faces[keep])


def vertex_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(N, 3) unit vertex normals: the area-weighted sum of the adjacent faces' normals.

    A vertex without faces gets (0, 0, 1) (facing a camera that looks along -z).
    """
    v = np.asarray(vertices, dtype=np.float64)
    fn = np.cross(v[faces[:, 1]] - v[faces[:, 0]], v[faces[:, 2]] - v[faces[:, 0]])  # length = 2 x area
    n = np.zeros_like(v)
    for k in range(3):
        np.add.at(n, faces[:, k], fn)
    length = np.linalg.norm(n, axis=1, keepdims=True)
    out = np.where(length > 0, n / np.maximum(length, 1e-300), np.array([0.0, 0.0, 1.0]))
    return out


@dataclass
class ObjectMesh:
    """One object cut from the image mesh.

    Attributes:
        label: the object's mask label.
        vertices: (N, 3) camera-frame positions, metres.
        normals: (N, 3) unit shading normals, facing the camera.
        faces: (F, 3) int64, facing the camera.
        pixels: (N,) flat pixel index i W + j of each vertex in the image mesh.
    """

    label: int
    vertices: np.ndarray
    normals: np.ndarray
    faces: np.ndarray
    pixels: np.ndarray


def object_mesh(mesh: ImageMesh, labels: np.ndarray, label: int, normals: np.ndarray | None = None) -> ObjectMesh:
    """The triangles of ``mesh`` whose three vertices carry ``label``.

    Args:
        labels: (H, W) integer object labels of the mesh's pixels (0 = background).
        normals: optional (H, W, 3) camera-frame per-pixel normals (e.g. from an estimator);
            by default the mesh's own vertex normals (computed on the object's triangles only,
            so the background does not bend them at the silhouette).
    """
    lab = np.asarray(labels).ravel()
    inside = lab[mesh.faces] == label
    faces = mesh.faces[inside.all(1)]
    if len(faces) == 0:
        raise RoomlightError(f"object {label}: no triangle of the depth mesh lies inside it "
                             "(too small at this resolution, or cut by depth discontinuities)")
    used, local = np.unique(faces, return_inverse=True)
    faces = local.reshape(-1, 3).astype(np.int64)
    verts = mesh.vertices[used]
    if normals is not None:
        n = np.asarray(normals, dtype=np.float64).reshape(-1, 3)[used]
        n = n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
    else:
        n = vertex_normals(verts, faces)
    # Shading normals must face the camera (at the origin): a normal pointing away from it would
    # make the one-sided BSDF black.
    away = np.einsum("ij,ij->i", n, -verts) < 0
    n[away] = -n[away]
    return ObjectMesh(int(label), verts, n, faces, used.astype(np.int64))
