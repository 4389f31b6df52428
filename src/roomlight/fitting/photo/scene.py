"""The photograph's objects and camera as Mitsuba objects, in the room frame of the light."""

from __future__ import annotations

from roomlight.fitting.photo.camera import PhotoCamera
from roomlight.fitting.photo.geometry import SceneTransform
from roomlight.fitting.photo.materials import object_id
from roomlight.fitting.photo.unproject import ObjectMesh
from roomlight.core.render.materials import principled_bsdf
from roomlight.core.render.mesh import mitsuba_mesh

__all__ = ["object_shape", "object_shapes", "photo_sensor"]


def object_shape(obj: ObjectMesh, transform: SceneTransform, bsdf: dict | None = None, kind: str = "object"):
    """A ``mi.Mesh`` (id ``<kind>_<label>``) of one object (or shadow receiver) in the room frame, with its
    shading normals and a BSDF (default: the principled material at 0.5 everywhere)."""
    v = transform.points(obj.vertices)
    n = transform.directions(obj.normals)
    return mitsuba_mesh(object_id(obj.label, kind), v, obj.faces, bsdf or principled_bsdf([0.5] * 3, 0.5, 0.5),
                        normals=n)


def object_shapes(objects: list[ObjectMesh], transform: SceneTransform, bsdfs: dict[int, dict] | None = None,
                  kind: str = "object") -> dict:
    """Every object's (or receiver's) mesh by id (to pass as ``EmitterScene(objects=...)``)."""
    bsdfs = bsdfs or {}
    return {object_id(o.label, kind): object_shape(o, transform, bsdfs.get(o.label), kind) for o in objects}


def photo_sensor(intrinsics: PhotoCamera, transform: SceneTransform) -> dict:
    """The photograph's camera as a Mitsuba sensor dict in the room frame (box pixel filter)."""
    from roomlight.core.render.camera import pinhole_sensor

    intrinsics.check_square_pixels()
    return pinhole_sensor(intrinsics.fx, intrinsics.cx, intrinsics.cy, intrinsics.width, intrinsics.height,
                          origin=transform.translation.tolist(), forward=transform.forward.tolist(),
                          up=transform.up.tolist())
