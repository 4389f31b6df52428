"""A triangle mesh cut to a photograph's view and textured by projection into it.

``roomlight insert`` builds its local scene from the photograph's depth map: one sheet of triangles from
the camera. To ask what that sheet's shape costs, the same local scene can be built from a scene's own
triangles (the photo benchmark knows its rooms): cut to the camera's frustum, so that it stands where the
depth sheet stood and the light keeps every direction outside the view, and given texture coordinates
that are each vertex's position in the photograph, so that an image-space albedo lands on the surface the
photograph shows there.

Texture coordinates are interpolated linearly across a triangle while the projection is not; triangles are
therefore split until every edge spans at most ``max_edge_px`` pixels of the image, where that difference
is a fraction of a pixel.

Frames as :mod:`roomlight.fitting.photo.camera`: camera frame x right, y up, looking along -z; texture
coordinates (u, v) = (x / W, y / H) of the pixel position, v = 0 on the top row (Mitsuba's bitmap
convention, the depth mesh's too).
"""

from __future__ import annotations

import math

import numpy as np

from roomlight.errors import RoomlightError

__all__ = ["frustum_planes", "clip_to_view", "subdivide_in_view", "view_uv", "mesh_in_view"]

#: Nearest distance along the optical axis kept by the cut (metres): a point at the camera has no pixel.
NEAR_M = 1e-3


def frustum_planes(intrinsics, margin_px: float = 1.0, near: float = NEAR_M) -> np.ndarray:
    """(5, 4) planes (a, b, c, d) of the view, a point q (camera frame) inside when a q_x + b q_y + c q_z + d ≥ 0
    for all five: the image's four borders widened by ``margin_px`` pixels, and a near plane."""
    k = intrinsics
    x0, x1 = -margin_px, k.width + margin_px
    y0, y1 = -margin_px, k.height + margin_px
    # pixel x = cx + fx q_x / z' with z' = -q_z > 0:  x ≥ x0  <=>  fx q_x + (cx - x0) z' ≥ 0, etc.
    return np.array([
        [k.fx, 0.0, -(k.cx - x0), 0.0],
        [-k.fx, 0.0, -(x1 - k.cx), 0.0],
        [0.0, -k.fy, -(k.cy - y0), 0.0],      # pixel y = cy - fy q_y / z'
        [0.0, k.fy, -(y1 - k.cy), 0.0],
        [0.0, 0.0, -1.0, -near],
    ], np.float64)


def _clip_polygon(poly: list[np.ndarray], plane: np.ndarray) -> list[np.ndarray]:
    """Sutherland-Hodgman: the part of a convex polygon (list of (3,) points) on the positive side of a plane."""
    out = []
    n = len(poly)
    for i in range(n):
        a, b = poly[i], poly[(i + 1) % n]
        da, db = plane[:3] @ a + plane[3], plane[:3] @ b + plane[3]
        if da >= 0:
            out.append(a)
        if (da >= 0) != (db >= 0):
            out.append(a + (b - a) * (da / (da - db)))
    return out


def clip_to_view(vertices: np.ndarray, faces: np.ndarray, planes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The triangles' parts inside every plane (camera frame).

    Args:
        vertices: (N, 3) metres; faces: (F, 3) vertex indices; planes: (P, 4) as :func:`frustum_planes`.
    Returns:
        (vertices (M, 3) float64, faces (G, 3) int64): triangles wholly inside are kept as they are (their
        vertices shared); those across a plane are cut and fanned (their vertices their own).
    """
    v = np.asarray(vertices, np.float64).reshape(-1, 3)
    f = np.asarray(faces, np.int64).reshape(-1, 3)
    side = v @ planes[:, :3].T + planes[:, 3]                       # (N, P)
    inside = side >= 0
    tri_in = inside[f]                                              # (F, 3, P)
    whole = tri_in.all(axis=(1, 2))
    gone = (~tri_in).all(axis=1).any(axis=1)                        # all three corners outside one plane
    cut = ~whole & ~gone
    kept = f[whole]
    used = np.unique(kept)
    remap = np.full(len(v), -1, np.int64)
    remap[used] = np.arange(len(used))
    out_v, out_f = [v[used]], [remap[kept]]
    base = len(used)
    extra_v, extra_f = [], []
    for tri in f[cut]:
        poly = [v[i] for i in tri]
        for plane in planes:
            poly = _clip_polygon(poly, plane)
            if len(poly) < 3:
                break
        if len(poly) < 3:
            continue
        start = base + sum(len(p) for p in extra_v)
        extra_v.append(np.asarray(poly))
        extra_f.extend([start, start + i, start + i + 1] for i in range(1, len(poly) - 1))
    if extra_v:
        out_v.append(np.concatenate(extra_v))
        out_f.append(np.asarray(extra_f, np.int64))
    return np.concatenate(out_v), np.concatenate(out_f).reshape(-1, 3)


def _pixels(points: np.ndarray, intrinsics) -> np.ndarray:
    """(N, 2) pixel positions (x right, y down) of camera-frame points in front of the camera."""
    z = -points[:, 2]
    return np.stack([intrinsics.cx + intrinsics.fx * points[:, 0] / z, intrinsics.cy - intrinsics.fy * points[:, 1] / z], -1)


def view_uv(points: np.ndarray, intrinsics) -> np.ndarray:
    """(N, 2) texture coordinates of camera-frame points: their pixel position over the image size."""
    return _pixels(np.asarray(points, np.float64), intrinsics) / np.array([intrinsics.width, intrinsics.height], np.float64)


def _barycentric_grid(n: int) -> tuple[np.ndarray, np.ndarray]:
    """((n+1)(n+2)/2, 3) barycentric weights of a triangle's regular grid with n segments a side, and its
    (n², 3) faces, wound as the triangle."""
    index, weights = {}, []
    for i in range(n + 1):
        for j in range(n + 1 - i):
            index[i, j] = len(weights)
            weights.append(((n - i - j) / n, i / n, j / n))
    faces = []
    for i in range(n):
        for j in range(n - i):
            faces.append((index[i, j], index[i + 1, j], index[i, j + 1]))
            if i + j < n - 1:
                faces.append((index[i + 1, j], index[i + 1, j + 1], index[i, j + 1]))
    return np.asarray(weights), np.asarray(faces, np.int64)


def _longest_edge_px(v: np.ndarray, f: np.ndarray, intrinsics) -> np.ndarray:
    px = _pixels(v, intrinsics)[f]                                  # (F, 3, 2)
    return np.linalg.norm(px - np.roll(px, -1, axis=1), axis=-1).max(1)


def subdivide_in_view(vertices: np.ndarray, faces: np.ndarray, intrinsics, max_edge_px: float = 2.0,
                      max_segments: int = 256, max_rounds: int = 8) -> tuple[np.ndarray, np.ndarray]:
    """Split triangles (camera frame, in front of the camera) until every projected edge spans at most
    ``max_edge_px`` pixels: each too long is replaced by a regular grid of n² triangles, n from its longest
    projected edge; a grid even in space is not in the image (the part nearer the camera projects larger),
    so what is still too long is split again, up to ``max_rounds`` times.

    Returns (vertices (M, 3), only those the faces use; faces (G, 3)); a split triangle's vertices are its own (neighbours may meet
    at T-junctions, which a ray tracer does not see as gaps: the new vertices lie on the shared edge).
    """
    v = np.asarray(vertices, np.float64).reshape(-1, 3)
    f = np.asarray(faces, np.int64).reshape(-1, 3)
    if not len(f):
        return v[:0], f
    if (-v[np.unique(f), 2] <= 0).any():
        raise RoomlightError("subdivide_in_view: a vertex lies at or behind the camera; cut the mesh to the view first")
    for _ in range(max_rounds):
        segments = np.clip(np.ceil(_longest_edge_px(v, f, intrinsics) / max_edge_px), 1, max_segments).astype(np.int64)
        if (segments == 1).all():
            break
        out_v, out_f, base = [v], [f[segments == 1]], len(v)
        for n in np.unique(segments[segments > 1]):
            tris = f[segments == n]
            w, grid = _barycentric_grid(int(n))
            pts = np.einsum("kc,tcd->tkd", w, v[tris]).reshape(-1, 3)   # (T * K, 3)
            offsets = base + np.arange(len(tris))[:, None, None] * len(w)
            out_v.append(pts)
            out_f.append((grid[None] + offsets).reshape(-1, 3))
            base += len(pts)
        v, f = np.concatenate(out_v), np.concatenate(out_f)
    return _compact(v, f)


def _compact(v: np.ndarray, f: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The vertices the faces use, in their order, and the faces renumbered."""
    used = np.unique(f)
    remap = np.full(len(v), -1, np.int64)
    remap[used] = np.arange(len(used))
    return v[used], remap[f]


def mesh_in_view(vertices: np.ndarray, faces: np.ndarray, intrinsics, max_edge_px: float = 2.0,
                 margin_px: float = 1.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A camera-frame mesh cut to the view (:func:`clip_to_view`), split fine (:func:`subdivide_in_view`) and
    textured by projection (:func:`view_uv`): (vertices (M, 3), faces (G, 3), uv (M, 2))."""
    v, f = clip_to_view(vertices, faces, frustum_planes(intrinsics, margin_px))
    v, f = subdivide_in_view(v, f, intrinsics, max_edge_px)
    if not math.isfinite(float(np.abs(v).sum())):
        raise RoomlightError("mesh_in_view: non-finite vertices")
    return v, f, view_uv(v, intrinsics)
