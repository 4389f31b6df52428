"""Shadow receivers: the surface each object stands on, fitted as a receiver of the light.

The frustum term reads the visible room as the light itself: a floor pixel is a texel of the emitter,
shadows and all. That pins the light's radiance where the photograph looks, but it says nothing about the
light the photograph does *not* show, and a single photograph cannot split the objects' brightness
between their albedo and that unseen light (twice the light on half the albedo). The floor around an
object can: where the object hides part of the room from the floor, the floor is darker, and the ratio of
shadowed to unshadowed floor is the share of the floor's irradiance that came through the hidden
directions. That ratio holds whatever the floor's albedo, so it bounds the unseen light (a lamp above the
object, a window beside it) against the seen room, whose radiance the frustum term already fixes.

Each object gets one receiver: the upward-facing background pixels around it, out to ``radius`` times the
object's size in the image, reached from the object through such pixels only (so a receiver never jumps a
depth edge onto a wall or another surface). The object's silhouette is itself a depth edge, whose pixels
have no reliable normal: the reach may cross the first ``_SILHOUETTE_PX`` pixels around the object without
taking them. The receiver is the depth mesh of those pixels with one
uniform diffuse-like material of its own (albedo fitted, roughness 1, no metal), rendered with the objects
casting their shadows on it and compared with the photograph: the image loss of the objects, on these
pixels. The 2.5D light is already held 2 % behind every surface the camera sees (containment), so the
receiver sits in front of the emitter's own floor.

Assumption: each receiver's albedo is uniform (one floor, one table top). A patterned rug breaks it; its
pattern then reads as light, as an object's texture does.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from roomlight.errors import RoomlightError
from roomlight.fitting.photo.unproject import ObjectMesh

__all__ = ["ShadowReceivers", "shadow_receivers", "receiver_labels", "locally_flat"]

#: Background pixels this close to an object (8-connected steps) may be crossed, not taken: the depth edge
#: of the object's silhouette leaves them without a reliable normal.
_SILHOUETTE_PX = 2
# The eight neighbours of a pixel.
_SHIFTS = [(dy, dx) for dy in (-1, 0, 1) for dx in (-1, 0, 1) if (dy, dx) != (0, 0)]


def _shifted(a: np.ndarray, dy: int, dx: int, fill) -> np.ndarray:
    """``a`` moved by (dy, dx): out[y, x] = a[y - dy, x - dx], ``fill`` where that falls outside."""
    h, w = a.shape
    out = np.full_like(a, fill)
    ys, yd = (slice(0, h - dy), slice(dy, h)) if dy >= 0 else (slice(-dy, h), slice(0, h + dy))
    xs, xd = (slice(0, w - dx), slice(dx, w)) if dx >= 0 else (slice(-dx, w), slice(0, w + dx))
    out[yd, xd] = a[ys, xs]
    return out


def locally_flat(points: np.ndarray, tolerance: float = 0.02) -> np.ndarray:
    """Whether each pixel and its four neighbours lie on one smooth surface.

    A straight image line maps to a straight line on a plane whatever the perspective's foreshortening, so
    a pixel on a flat surface lies on the line through its left and right neighbours (and through its upper
    and lower ones). The test is its distance from both lines, relative to its distance from the camera.
    Unlike a bound on the neighbours' depth ratio, it holds on a floor seen at a grazing angle, whose depth
    grows by more than 5 % from one pixel to the next there, and still fails across a depth edge.

    Args:
        points: (H, W, 3) the point each pixel sees (camera at the origin), metres.
        tolerance: the largest distance from those lines, as a fraction of the pixel's distance.
    Returns:
        (H, W) bool, False on the image border.
    """
    p = np.asarray(points, dtype=np.float64)
    h, w, _ = p.shape
    ok = np.zeros((h, w), bool)
    if h < 3 or w < 3:
        return ok
    c = p[1:-1, 1:-1]
    dist = np.linalg.norm(c, axis=-1)
    good = np.ones((h - 2, w - 2), bool)
    for a, b in ((p[1:-1, :-2], p[1:-1, 2:]), (p[:-2, 1:-1], p[2:, 1:-1])):
        line = b - a
        off = np.linalg.norm(np.cross(c - a, line), axis=-1) / np.maximum(np.linalg.norm(line, axis=-1), 1e-12)
        good &= off <= tolerance * dist
    ok[1:-1, 1:-1] = good
    return ok


def receiver_labels(labels: np.ndarray, normals: np.ndarray, normal_ok: np.ndarray, up: np.ndarray,
                    radius: float = 0.5, min_up: float = 0.7) -> np.ndarray:
    """Which background pixel belongs to which object's receiver.

    Args:
        labels: (H, W) int object labels (0 = background).
        normals: (H, W, 3) camera-frame unit normals of the surfaces the pixels see.
        normal_ok: (H, W) bool, whether a pixel's normal is reliable (no depth edge next to it).
        up: (3,) the room's up direction in the camera frame.
        radius: how far a receiver reaches from its object, in units of the object's size in the image
            (the larger side of its bounding box, pixels).
        min_up: a receiver pixel's normal has at least this cosine with ``up`` (a floor, a table top).
    Returns:
        (H, W) int32: the label of the object whose receiver a pixel is, 0 elsewhere (objects included).
        A pixel within reach of two objects goes to the one it is nearer to (in 8-connected steps through
        upward-facing pixels and the silhouette's band; ties to the neighbour met first in a fixed order),
        so the result is deterministic.
    """
    labels = np.asarray(labels)
    up = np.asarray(up, dtype=np.float64)
    up = up / np.linalg.norm(up)
    candidate = (labels == 0) & np.asarray(normal_ok, bool) & (np.asarray(normals) @ up >= min_up)
    ids = [int(v) for v in np.unique(labels) if v != 0]
    if not ids:
        return np.zeros(labels.shape, np.int32)
    reach = np.zeros(int(max(ids)) + 1, np.int64)
    for i in ids:
        ys, xs = np.nonzero(labels == i)
        size = max(ys.max() - ys.min() + 1, xs.max() - xs.min() + 1)
        reach[i] = max(2, int(round(radius * size)))
    near = labels != 0
    for _ in range(_SILHOUETTE_PX):
        near = near | np.any([_shifted(near, dy, dx, False) for dy, dx in _SHIFTS], axis=0)
    passable = candidate | (near & (labels == 0))
    owner = labels.astype(np.int64).copy()
    for step in range(1, int(reach.max()) + 1):
        grown = owner.copy()
        for dy, dx in _SHIFTS:
            nb = _shifted(owner, dy, dx, 0)
            take = (grown == 0) & passable & (nb > 0) & (reach[nb] >= step)
            grown[take] = nb[take]
        if np.array_equal(grown, owner):
            break
        owner = grown
    return np.where(candidate, owner, 0).astype(np.int32)


@dataclass
class ShadowReceivers:
    """The shadow receivers of a photo fit.

    Attributes:
        meshes: one per object that has a receiver, cut from the depth mesh and labelled with its object's label.
        labels: (Hr, Wr) int32 the receiver each render pixel belongs to (its object's label), 0 elsewhere.
        mask: (Hr, Wr) bool the receiver pixels the receivers' image term sees (all eight neighbours in the
            same receiver, as for the objects).
    """

    meshes: list[ObjectMesh]
    labels: np.ndarray
    mask: np.ndarray


def shadow_receivers(geometry, case, config) -> ShadowReceivers | None:
    """The receivers of a photograph prepared for fitting (:class:`~roomlight.fitting.photo.geometry.PhotoGeometry`
    of ``case`` under ``config``), or None when no object has one. A receiver too small to keep a triangle of
    the depth mesh or an interior pixel is left out."""
    from roomlight.fitting.photo.camera import camera_rotation
    from roomlight.fitting.photo.geometry import _interior
    from roomlight.fitting.photo.masks import resize_nearest
    from roomlight.fitting.photo.room_albedo import surface_normals
    from roomlight.fitting.photo.unproject import object_mesh

    if not geometry.objects:
        return None
    rh, rw = geometry.labels.shape
    points = geometry.pixel_points.reshape(rh, rw, 3)
    normals, _ = surface_normals(points, config.edge_tolerance)
    up = camera_rotation(case.pitch_deg, case.roll_deg).T @ np.array([0.0, 1.0, 0.0])
    rec = receiver_labels(geometry.labels, normals, locally_flat(points), up, config.receiver_radius,
                          config.receiver_min_up)
    inner = _interior(rec)
    gh, gw = geometry.mesh.shape
    rec_g = resize_nearest(rec, gh, gw)
    normals_g = resize_nearest(case.normals, gh, gw) if case.normals is not None else None
    meshes = []
    for label in sorted(int(v) for v in np.unique(rec[inner])):
        try:
            meshes.append(object_mesh(geometry.mesh, rec_g, label, normals_g))
        except RoomlightError:
            continue
    if not meshes:
        return None
    rec = np.where(np.isin(rec, [m.label for m in meshes]), rec, 0).astype(np.int32)
    return ShadowReceivers(meshes, rec, inner & (rec != 0))
