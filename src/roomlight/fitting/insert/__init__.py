"""Putting virtual objects into a photograph under its recovered light: ``roomlight insert``.

A ``fit-photo`` output folder is read back (:mod:`roomlight.fitting.insert.fitted`), the objects are placed
on the photograph's surfaces (:mod:`roomlight.fitting.insert.objects`) and composited by differential
rendering (:mod:`roomlight.fitting.insert.composite`). See docs/photo.md.
"""

from roomlight.fitting.insert.composite import (ALBEDO_RANGE, InsertResult, composite_objects, estimate_albedo, insert_objects,
                                       place_objects)
from roomlight.fitting.insert.fitted import FittedPhoto, fitted_lights, load_fitted_photo
from roomlight.fitting.insert.objects import InsertSpec, PlacedObject, parse_material, place_object, read_placements
from roomlight.fitting.insert.outputs import write_insert_outputs

__all__ = ["ALBEDO_RANGE", "InsertResult", "composite_objects", "estimate_albedo", "insert_objects", "place_objects", "FittedPhoto", "fitted_lights",
           "load_fitted_photo", "InsertSpec", "PlacedObject", "parse_material", "place_object", "read_placements",
           "write_insert_outputs"]
