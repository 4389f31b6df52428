"""The 2.5D area light behind any roomlight output, and its export to glTF, USD and OBJ.

``load_light`` finds the light (an emitter bundle, a fit, a sample, a benchmark case);
``export_light`` writes it. The formats and the emission scale are in docs/file-formats.md.
"""

from roomlight.export.bundle import LightSource, SceneObject, load_light
from roomlight.export.formats import FORMATS, emission_strength, export_light, linear_to_srgb

__all__ = ["LightSource", "SceneObject", "load_light", "FORMATS", "emission_strength", "export_light",
           "linear_to_srgb"]
