"""A Mitsuba scene around one roomlight emitter, updated in place between renders.

The emitter is one of three kinds (the paper's representations):

- ``mesh``:   the 2.5D area light; depth moves the vertices, radiance is its texture.
- ``sphere``: the same mesh at a constant radius (a sphere proxy); depth is ignored.
- ``envmap``: the radiance at infinity (Mitsuba ``envmap``), resampled to its row layout.

Topology, UVs and the Mitsuba objects are created once; :meth:`EmitterScene.set_emitter`
only writes new vertex positions / texture values through ``mi.traverse`` and calls
``params.update()``, so no scene is reloaded between renders or optimisation steps.
"""

from __future__ import annotations

import numpy as np
import torch

from roomlight.core.emitter.area_light import area_light_topology, area_light_vertices
from roomlight.core.emitter.envmap import envmap_data, envmap_rows
from roomlight.core.emitter.sphere import sphere_depth
from roomlight.errors import RoomlightError, ShapeError
from roomlight.core.light import EmitterKind, parse_emitter_kind
from roomlight.core.render.tensors import from_mitsuba_tensor, to_mitsuba_tensor
from roomlight.core.render.variant import mitsuba

# EmitterKind and parse_emitter_kind live in roomlight.core.light; re-exported for old imports.
__all__ = ["EmitterScene", "EMITTER_ID", "EMITTER_BSDF", "EmitterKind", "parse_emitter_kind"]

EMITTER_ID = "emitter"

#: The emitter is a light source only: it must not reflect (Mitsuba's default BSDF is a 50 % grey
#: diffuse surface, which would add bounce light). A black *smooth* BSDF would still make the
#: integrator sample a light from every emitter hit (a shadow ray through the whole mesh, for
#: nothing); a black *delta* BSDF has no smooth component, so paths that reach the emitter end there.
EMITTER_BSDF = {"type": "conductor", "specular_reflectance": {"type": "rgb", "value": [0.0, 0.0, 0.0]}}


def _texture_dict(mi, radiance_hwc: np.ndarray) -> dict:
    # raw=True keeps the float data as linear radiance (no colour-space conversion); repeat
    # wrapping resolves the seam column's u = 1 + 0.5/W to texel 0.
    return {"type": "bitmap", "data": mi.TensorXf(radiance_hwc), "raw": True,
            "filter_type": "bilinear", "wrap_mode": "repeat"}


class EmitterScene:
    """A scene with one roomlight emitter (shape id ``emitter``) plus optional objects.

    Args:
        kind: ``mesh``, ``envmap``, ``sphere:R`` or an :class:`EmitterKind`.
        resolution: (H, W) of the radiance (and depth) maps this scene will receive.
        objects: extra scene entries (Mitsuba dicts or instantiated objects), keyed by id.
        sensor: a Mitsuba sensor dict (see :mod:`roomlight.core.render.camera`), or None.
        integrator: a Mitsuba integrator dict; default ``prb`` with max depth 4 (the paper's).
    """

    def __init__(self, kind="mesh", resolution=(128, 256), objects: dict | None = None,
                 sensor: dict | None = None, integrator: dict | None = None):
        self.mi = mi = mitsuba()
        self.kind = parse_emitter_kind(kind)
        h, w = resolution
        if w != 2 * h:
            raise ShapeError(f"EmitterScene: resolution must be H x 2H, got {h}x{w}")
        self.resolution = (h, w)
        gray = np.full((h, w, 3), 1.0, np.float32)
        scene: dict = {"type": "scene"}
        if integrator is None:
            integrator = {"type": "prb", "max_depth": 4}
        scene["integrator"] = integrator
        if sensor is not None:
            scene["sensor"] = sensor
        if self.kind.name == "envmap":
            data = np.full((envmap_rows(h), w, 3), 1.0, np.float32)
            scene[EMITTER_ID] = {"type": "envmap", "bitmap": mi.Bitmap(data)}
            self._tex_key = f"{EMITTER_ID}.data"
            self._pos_key = None
        else:
            topo = area_light_topology(h, w)
            props = mi.Properties()
            props["emitter"] = mi.load_dict({"type": "area", "radiance": _texture_dict(mi, gray)})
            props["bsdf"] = mi.load_dict(EMITTER_BSDF)
            mesh = mi.Mesh(EMITTER_ID, topo.vertex_count, topo.face_count, props,
                           has_vertex_normals=False, has_vertex_texcoords=True)
            mp = mi.traverse(mesh)
            # the sphere proxy keeps these vertices; a 2.5D light replaces them on set_emitter
            depth0 = sphere_depth(h, w, self.kind.radius or 1.0, torch.float32)
            mp["vertex_positions"] = mi.Float(area_light_vertices(depth0).numpy().ravel())
            mp["faces"] = mi.UInt(topo.faces.numpy().astype(np.uint32).ravel())
            mp["vertex_texcoords"] = mi.Float(topo.uv.numpy().ravel())
            mp.update()
            scene[EMITTER_ID] = mesh
            self._tex_key = f"{EMITTER_ID}.emitter.radiance.data"
            self._pos_key = f"{EMITTER_ID}.vertex_positions"
        for key, value in (objects or {}).items():
            if key in scene:
                raise RoomlightError(f"EmitterScene: object id {key!r} is reserved")
            scene[key] = value
        self.scene = mi.load_dict(scene)
        self.params = mi.traverse(self.scene)

    # -- conversions torch -> the values stored in the scene (differentiable in torch) ----------
    def texture_value(self, radiance: torch.Tensor) -> torch.Tensor:
        """(H, W, 3) radiance -> the tensor the emitter's texture parameter holds."""
        if tuple(radiance.shape) != (*self.resolution, 3):
            raise ShapeError(f"EmitterScene: expected radiance {(*self.resolution, 3)}, got {tuple(radiance.shape)}")
        return envmap_data(radiance) if self.kind.name == "envmap" else radiance

    def vertex_value(self, depth: torch.Tensor | None) -> torch.Tensor | None:
        """(H, W) depth -> flat (3N,) vertex positions; None when there is nothing to write: the
        env map has no vertices, and the sphere proxy's fixed vertices were written when the scene
        was built (re-writing them would rebuild the ray-tracing BVH on every render)."""
        if self._pos_key is None or self.kind.name == "sphere":
            return None
        if depth is None:
            raise RoomlightError("EmitterScene: a 'mesh' emitter needs a depth map")
        if tuple(depth.shape[-2:]) != self.resolution:
            raise ShapeError(f"EmitterScene: expected depth {self.resolution}, got {tuple(depth.shape)}")
        return area_light_vertices(depth.reshape(self.resolution)).reshape(-1)

    # -- in-place updates and plain (non-differentiable) rendering ---------------------------
    def write_emitter_values(self, texture, vertices=None) -> None:
        """Store already-converted values in the scene and update it (no reload).

        Args:
            texture: the emitter texture as Mitsuba holds it (``mi.TensorXf`` or a Dr.Jit tensor
                attached to an AD graph): (H, W, 3) for a mesh, (H + 1, W + 2, 3) for an env map
                (see :meth:`texture_value`).
            vertices: flat (3N,) vertex positions (``mi.Float``), or None to keep the current
                ones (see :meth:`vertex_value`).
        """
        self.params[self._tex_key] = texture
        if vertices is not None:
            if self._pos_key is None:
                raise RoomlightError(f"EmitterScene: an {self.kind} emitter has no vertices to write")
            self.params[self._pos_key] = vertices
        self.params.update()

    def set_emitter(self, radiance: torch.Tensor, depth: torch.Tensor | None = None) -> None:
        """Write new radiance (H, W, 3) and depth (H, W) into the scene, without reloading it."""
        with torch.no_grad():
            tex = to_mitsuba_tensor(self.texture_value(radiance.float()))
            verts = self.vertex_value(depth.float() if depth is not None else None)
        self.write_emitter_values(tex, self.mi.Float(verts.numpy()) if verts is not None else None)

    def parameter_value(self, key: str, value):
        """A Dr.Jit tensor (e.g. from :func:`drjit.wrap`) -> the type the scene parameter ``key`` holds.

        Colours (``Color3f``, e.g. a BSDF's ``base_color.value``) take 3 values; scalar fields
        (``Float``, e.g. ``roughness.value``) take 1. Attached gradients are kept.
        """
        import drjit as dr

        mi = self.mi
        if key not in self.params:
            raise RoomlightError(f"EmitterScene: the scene has no parameter {key!r}")
        current = self.params[key]
        flat = value.array if hasattr(value, "array") else value
        if isinstance(current, mi.Color3f):
            if dr.width(flat) != 3:
                raise ShapeError(f"EmitterScene: {key} is a colour and takes 3 values, got {dr.width(flat)}")
            return dr.unravel(mi.Color3f, flat)
        if dr.width(flat) != dr.width(current):
            raise ShapeError(f"EmitterScene: {key} takes {dr.width(current)} value(s), got {dr.width(flat)}")
        return flat

    def set_parameters(self, values: dict[str, torch.Tensor]) -> None:
        """Write plain (non-differentiable) values of scene parameters by key and update the scene."""
        if not values:
            return
        for key, value in values.items():
            v = self.mi.Float(value.detach().to("cpu", torch.float32).reshape(-1).numpy())
            self.params[key] = self.parameter_value(key, v)
        self.params.update()

    def cropped_sensor(self, sensor: dict, window: tuple[int, int, int, int]):
        """A Mitsuba sensor that renders only ``window`` = (x0, y0, width, height) pixels of the
        film of ``sensor`` (a sensor dict of this scene's camera, see
        :func:`roomlight.core.render.camera.cropped_sensor`); pass it as ``sensor=`` to :meth:`render`
        or to :func:`roomlight.core.render.bridge.render_differentiable`."""
        from roomlight.core.render.camera import cropped_sensor

        x0, y0, w, h = window
        return self.mi.load_dict(cropped_sensor(sensor, x0, y0, w, h))

    def render(self, spp: int = 64, seed: int = 0, sensor: int | object = 0) -> torch.Tensor:
        """Render the current scene; returns (H, W, 3) float32 linear radiance on the CPU."""
        img = self.mi.render(self.scene, spp=spp, seed=seed, sensor=sensor)
        return from_mitsuba_tensor(img)[..., :3]
