"""Scene descriptions (cameras, objects, materials, views, emitter) and their Mitsuba form.

- :mod:`roomlight.fitting.scene.description`  the ``scene.json`` / ``scene.yaml`` format: parse, validate, save
- :mod:`roomlight.fitting.scene.shapes`       the built-in non-convex test shapes
- :mod:`roomlight.fitting.scene.build`        files and Mitsuba objects: ``load_scene`` (reads every file a
  scene names), meshes, target images and masks, surface points
"""

from roomlight.fitting.scene.build import check_scene_files, load_scene
from roomlight.fitting.scene.description import (
    CameraSpec, EmitterSpec, MaterialSpec, ObjectSpec, SceneError, SceneSpec, ViewSpec, read_scene, save_scene,
)
from roomlight.fitting.scene.shapes import BUILTIN_SHAPES, builtin_shape

__all__ = ["CameraSpec", "EmitterSpec", "MaterialSpec", "ObjectSpec", "SceneError", "SceneSpec", "ViewSpec",
           "load_scene", "read_scene", "check_scene_files", "save_scene", "BUILTIN_SHAPES", "builtin_shape"]
