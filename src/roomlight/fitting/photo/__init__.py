"""From one photograph to the room's light: ``roomlight fit-photo`` (paper §4.3, supp. "Real images").

A photograph, its metric depth (given, or from a monocular estimator), the camera intrinsics and a
mask of the objects of interest become a depth mesh cut into objects; the room's light (the
prior's 2.5D area light, or an env-map baseline) and one principled material per object are
fitted jointly through Mitsuba, with the photograph's unmasked pixels constraining the light
inside the camera's frustum. See docs/photo.md.
"""

from roomlight.fitting.photo.camera import PhotoCamera, camera_rotation
from roomlight.fitting.photo.case import PhotoCase, load_photo, write_photo_case
from roomlight.fitting.photo.config import PHOTO_PRESETS, PhotoFitConfig, photo_config
from roomlight.fitting.photo.estimator import GeometryEstimate, MoGeEstimator, resolve_estimator
from roomlight.fitting.photo.fitter import PHOTO_METHODS, PhotoFit, PhotoFitter, PhotoModel, fit_photo
from roomlight.fitting.photo.masks import ObjectLabels, connected_components, read_mask
from roomlight.fitting.photo.materials import ObjectMaterials
from roomlight.fitting.photo.pipeline import PhotoRun, run_photo
from roomlight.fitting.photo.unproject import image_mesh, object_mesh, unproject

__all__ = ["PhotoCamera", "camera_rotation", "PhotoCase", "load_photo", "write_photo_case", "PHOTO_PRESETS",
           "PhotoFitConfig", "photo_config", "GeometryEstimate", "MoGeEstimator", "resolve_estimator", "PHOTO_METHODS",
           "PhotoFit", "PhotoFitter", "PhotoModel", "fit_photo", "ObjectLabels", "connected_components", "read_mask",
           "ObjectMaterials", "PhotoRun", "run_photo", "image_mesh", "object_mesh", "unproject"]
