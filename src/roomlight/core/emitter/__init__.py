"""A panorama as a light source: the 2.5D area light (an emissive triangle mesh over the radial depth),
the env map's resampled rows, the sphere proxy's depth, and the bundle (PLY + EXR + scene.xml) that
``roomlight emitter`` writes for other renderers.
"""

from __future__ import annotations

from roomlight.core.emitter.area_light import (AreaLightMesh, AreaLightTopology, area_light_topology,
                                               area_light_vertices, build_area_light)
from roomlight.core.emitter.envmap import envmap_data, envmap_rows
from roomlight.core.emitter.export import export_emitter, scene_xml
from roomlight.core.emitter.sphere import sphere_depth

__all__ = ["AreaLightMesh", "AreaLightTopology", "area_light_topology", "area_light_vertices", "build_area_light",
           "envmap_data", "envmap_rows", "export_emitter", "scene_xml", "sphere_depth"]
