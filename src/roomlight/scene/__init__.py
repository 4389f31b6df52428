"""Scene descriptions (cameras, objects, materials, views, emitter) and their Mitsuba form."""

from roomlight.scene.description import (
    CameraSpec, EmitterSpec, MaterialSpec, ObjectSpec, SceneError, SceneSpec, ViewSpec, load_scene, save_scene,
)
from roomlight.scene.shapes import BUILTIN_SHAPES, builtin_shape

__all__ = ["CameraSpec", "EmitterSpec", "MaterialSpec", "ObjectSpec", "SceneError", "SceneSpec", "ViewSpec",
           "load_scene", "save_scene", "BUILTIN_SHAPES", "builtin_shape"]
