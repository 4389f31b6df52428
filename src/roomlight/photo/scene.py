"""The photograph's objects and camera as Mitsuba objects, in the room frame of the light."""

from __future__ import annotations

import numpy as np

from roomlight.photo.camera import Intrinsics
from roomlight.photo.geometry import SceneTransform
from roomlight.photo.materials import object_id, principled_bsdf
from roomlight.photo.unproject import ObjectMesh

__all__ = ["object_shape", "object_shapes", "photo_sensor"]


def object_shape(obj: ObjectMesh, transform: SceneTransform, bsdf: dict | None = None):
    """A ``mi.Mesh`` (id ``object_<label>``) of one object in the room frame, with its shading
    normals and a BSDF (default: the principled material at 0.5 everywhere)."""
    from roomlight.render.variant import mitsuba

    mi = mitsuba()
    v = transform.points(obj.vertices).astype(np.float32)
    n = transform.directions(obj.normals).astype(np.float32)
    props = mi.Properties()
    props["bsdf"] = mi.load_dict(bsdf or principled_bsdf([0.5] * 3, 0.5, 0.5))
    mesh = mi.Mesh(object_id(obj.label), len(v), len(obj.faces), props, has_vertex_normals=True)
    p = mi.traverse(mesh)
    p["vertex_positions"] = mi.Float(v.ravel())
    p["vertex_normals"] = mi.Float(n.ravel())
    p["faces"] = mi.UInt(obj.faces.astype(np.uint32).ravel())
    p.update()
    return mesh


def object_shapes(objects: list[ObjectMesh], transform: SceneTransform, bsdfs: dict[int, dict] | None = None) -> dict:
    """Every object's mesh by id (to pass as ``EmitterScene(objects=...)``)."""
    bsdfs = bsdfs or {}
    return {object_id(o.label): object_shape(o, transform, bsdfs.get(o.label)) for o in objects}


def photo_sensor(intrinsics: Intrinsics, transform: SceneTransform) -> dict:
    """The photograph's camera as a Mitsuba sensor dict in the room frame (box pixel filter)."""
    from roomlight.render.camera import pinhole_sensor

    intrinsics.check_square_pixels()
    return pinhole_sensor(intrinsics.fx, intrinsics.cx, intrinsics.cy, intrinsics.width, intrinsics.height,
                          origin=transform.translation.tolist(), forward=transform.forward.tolist(),
                          up=transform.up.tolist())
