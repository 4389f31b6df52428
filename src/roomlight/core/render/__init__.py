"""Rendering with Mitsuba 3: the variant (LLVM on a CPU, CUDA on a GPU) and thread policy, the emitter
scene that shows a light as a 2.5D area light, env map or sphere proxy, the torch <-> Dr.Jit bridge that
differentiates a render with respect to radiance and depth, cameras, materials, meshes and ray casts.

Mitsuba itself loads on first use (:func:`mitsuba`), not when this package is imported.
"""

from __future__ import annotations

from roomlight.core.render.bridge import render_differentiable
from roomlight.core.render.bundle import Probe, load_emitter_scene, parse_probe, render_bundle
from roomlight.core.render.camera import cropped_sensor, perspective_sensor, pinhole_sensor
from roomlight.core.render.materials import MATERIALS, material, principled_bsdf
from roomlight.core.render.mesh import mitsuba_mesh
from roomlight.core.render.raycast import RayCaster, render_in_passes, shape_coverage, sphere_directions
from roomlight.core.render.scene import EMITTER_ID, EmitterScene
from roomlight.core.render.variant import ensure_variant, mitsuba, recheck_threads, torch_device

__all__ = ["render_differentiable", "Probe", "load_emitter_scene", "parse_probe", "render_bundle", "cropped_sensor",
           "perspective_sensor", "pinhole_sensor", "MATERIALS", "material", "principled_bsdf", "mitsuba_mesh",
           "RayCaster", "render_in_passes", "shape_coverage", "sphere_directions", "EMITTER_ID", "EmitterScene",
           "ensure_variant", "mitsuba", "recheck_threads", "torch_device"]
