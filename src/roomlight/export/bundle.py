"""Finding the 2.5D area light behind a path: an emitter bundle, a fit, a sample or a benchmark case.

``load_light(path)`` accepts

- an emitter bundle (``emitter.ply`` + ``radiance.exr`` + ``depth.exr``, see docs/file-formats.md),
  including one of the ``sample_000/`` folders ``roomlight sample`` writes;
- a ``roomlight fit`` output folder (its ``emitter/`` bundle), or a benchmark result case
  (``.../<method>/`` holding ``fit/emitter/``);
- a ``roomlight fit-photo`` output folder: its light, and with it the photograph's camera (pose and
  intrinsics, in the light's room frame), the photograph's depth mesh (``depth_mesh``, for a shadow
  catcher) and the photograph itself (``backplate``, linear RGB);
- a folder of samples (the first ``sample_*`` bundle is taken);
- a benchmark case (a folder with ``scene.json``/``scene.yaml``, or the scene file itself): its
  true emitter panorama becomes the mesh, and its objects come along;
- a panorama EXR with depth (R, G, B, Z).

An env-map bundle has no mesh; its ``depth.exr``, when present, makes one.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from roomlight.errors import InputFileError
from roomlight.core.light import Light

if TYPE_CHECKING:
    from roomlight.fitting.insert.fitted import FittedPhoto

__all__ = ["SceneObject", "LightSource", "load_light"]

_SCENE_NAMES = ("scene.json", "scene.yaml", "scene.yml")


@dataclass
class SceneObject:
    """One object of a scene, in world space (metres)."""

    id: str
    vertices: np.ndarray  #: (N, 3) float32
    faces: np.ndarray     #: (F, 3) int32
    material: str         #: the scene's material type (diffuse, matte, mirror, ...)
    role: str = ""        #: which views show it ("input", "eval", ...)


@dataclass
class LightSource:
    """A 2.5D area light ready to be shown or exported.

    ``light`` is the panorama (a ``mesh`` :class:`~roomlight.core.light.Light`: linear radiance, radial
    metres; its capture point is the origin); ``vertices`` (N, 3), ``faces`` (F, 3) and ``uv`` (N, 2)
    the emissive mesh, with v = 0 at the texture's top row, as in the bundle's PLY.
    """

    light: Light
    vertices: np.ndarray
    faces: np.ndarray
    uv: np.ndarray
    source: str
    objects: list[SceneObject] = field(default_factory=list)
    camera: dict | None = None  #: origin / target / up / fov of the scene's first view, when known
    metadata: dict = field(default_factory=dict)
    #: (h, w, 3) linear RGB seen by ``camera`` (a fit-photo's photograph), or None
    backplate: np.ndarray | None = None
    #: the fit-photo output the light was read from (its objects' fitted materials), or None
    photo: FittedPhoto | None = None

    @property
    def radiance(self) -> np.ndarray:
        """(H, 2H, 3) float32 linear radiance (the light's, as numpy)."""
        return self.light.radiance.numpy()

    @property
    def depth(self) -> np.ndarray:
        """(H, 2H) float32 radial depth, metres (the light's, as numpy)."""
        return self.light.depth.numpy()

    def with_exposure(self, ev: float) -> "LightSource":
        """The same light 2^ev times as bright (mesh, camera, objects and backplate unchanged); the stops
        are added to ``metadata["exposure_ev"]``, which the exported files record.

        Raises:
            RoomlightError: ``ev`` not finite or outside [-10, 10] (:meth:`Light.with_exposure`).
        """
        light = self.light.with_exposure(ev)
        meta = {**self.metadata, "exposure_ev": float(self.metadata.get("exposure_ev", 0.0)) + float(ev)}
        return replace(self, light=light, metadata=meta)


def _mesh_from_panorama(light: Light):
    from roomlight.core.emitter.area_light import build_area_light

    mesh = build_area_light(light.radiance, light.depth)
    return mesh.vertices.numpy(), mesh.faces.numpy(), mesh.uv.numpy()


def _rgb(channels: dict, path: Path) -> np.ndarray:
    if not all(c in channels for c in "RGB"):
        raise InputFileError(path, f"expected channels R, G, B, found {', '.join(sorted(channels))}")
    return np.stack([channels[c] for c in "RGB"], -1).astype(np.float32)


def _from_bundle(d: Path) -> LightSource:
    from roomlight.core.io import read_depth, read_exr, read_ply

    radiance = _rgb(read_exr(d / "radiance.exr"), d / "radiance.exr")
    if not (d / "depth.exr").is_file():
        raise InputFileError(d, "this bundle has no depth.exr, so there is no 2.5D light to show",
                             "rebuild it with 'roomlight emitter PANO --as mesh'")
    light = Light(radiance, read_depth(d / "depth.exr"), "mesh")
    meta = json.loads((d / "emitter.json").read_text()) if (d / "emitter.json").is_file() else {}
    if (d / "emitter.ply").is_file():
        ply = read_ply(d / "emitter.ply")
        if "uv" not in ply:
            raise InputFileError(d / "emitter.ply", "the mesh has no texture coordinates (u, v)")
        v, f, uv = ply["vertices"], ply["faces"], ply["uv"]
    else:  # an env-map bundle that kept its depth
        v, f, uv = _mesh_from_panorama(light)
    return LightSource(light, v.astype(np.float32), f.astype(np.int32), uv.astype(np.float32), source=str(d),
                       metadata=meta)


def _scene_objects(scene) -> tuple[list[SceneObject], dict | None]:
    from roomlight.fitting.scene.build import object_geometry

    roles: dict[str, list[str]] = {}
    for name, view in scene.views.items():
        for oid in view.objects:
            roles.setdefault(oid, []).append(name)
    objects = []
    for obj in scene.objects.values():
        v, f = object_geometry(obj)
        objects.append(SceneObject(obj.id, v.astype(np.float32), f.astype(np.int32), obj.material.type,
                                   ",".join(roles.get(obj.id, []))))
    cam = next(iter(scene.views.values())).camera
    return objects, {"origin": list(cam.origin), "target": list(cam.target), "up": list(cam.up), "fov": cam.fov}


def _from_scene(path: Path) -> LightSource:
    from roomlight.fitting.scene.build import load_scene

    scene = load_scene(path, check_files=False)
    if scene.emitter is None:
        raise InputFileError(path, "the scene names no emitter panorama, so there is no light to show",
                             "pass a fit output or an emitter bundle instead")
    pano = scene.emitter.load()
    if pano.depth is None:
        raise InputFileError(scene.emitter.panorama, "the scene's emitter panorama has no depth")
    light = _from_panorama_arrays(pano.radiance, pano.depth, str(path))
    light.objects, light.camera = _scene_objects(scene)
    return light


def _from_panorama_arrays(radiance, depth, source: str) -> LightSource:
    light = Light(radiance, depth, "mesh")
    v, f, uv = _mesh_from_panorama(light)
    return LightSource(light, v, f.astype(np.int32), uv, source=source)


def _find_scene(d: Path) -> Path | None:
    """The scene a fit was run on, when a ``result.json`` next to or above it names one."""
    for parent in [d, *list(d.parents)[:3]]:
        info = parent / "result.json"
        if info.is_file():
            try:
                info = json.loads(info.read_text())
            except ValueError:
                continue
            for key in ("scene_path", "scene"):  # the benchmark runner writes scene_path
                scene = info.get(key) if isinstance(info, dict) else None
                if isinstance(scene, str) and Path(scene).is_file():
                    return Path(scene)
    return None


def _bundle_dir(p: Path) -> Path | None:
    """The emitter bundle folder a path leads to, if any."""
    for cand in (p, p / "emitter", p / "fit" / "emitter"):
        if (cand / "radiance.exr").is_file():
            return cand
    samples = sorted(q for q in p.glob("sample_*") if (q / "radiance.exr").is_file())
    return samples[0] if samples else None


def load_light(path, scene=None) -> LightSource:
    """The 2.5D area light behind ``path`` (see the module docstring), with ``scene``'s objects if given."""
    from roomlight.fitting.scene.build import load_scene

    p = Path(path)
    if not p.exists():
        raise InputFileError(p, "file does not exist")
    if p.is_file():
        if p.name in _SCENE_NAMES or p.suffix in (".json", ".yaml", ".yml"):
            light = _from_scene(p)
        else:
            from roomlight.core.io import read_panorama

            pano = read_panorama(p)
            if pano.depth is None:
                raise InputFileError(p, "the panorama has no depth channel (Z), so there is no 2.5D light")
            light = _from_panorama_arrays(pano.radiance, pano.depth, str(p))
    elif (bundle := _bundle_dir(p)) is not None:
        light = _from_bundle(bundle)
        scene = scene or _find_scene(p)
    elif (scene_file := next((p / n for n in _SCENE_NAMES if (p / n).is_file()), None)) is not None:
        light = _from_scene(scene_file)
    else:
        raise InputFileError(p, "no emitter here", "expected an emitter bundle (radiance.exr, depth.exr, "
                             "emitter.ply), a fit output (emitter/), samples (sample_*/) or a benchmark case "
                             "(scene.json)")
    if scene is not None and not light.objects:
        light.objects, light.camera = _scene_objects(load_scene(scene, check_files=False))
    if p.is_dir() and _is_photo_fit(p):
        _add_photo(light, p)
    return light


def _is_photo_fit(d: Path) -> bool:
    try:
        return json.loads((d / "result.json").read_text()).get("format") == "roomlight.photo-fit"
    except (OSError, ValueError, AttributeError):
        return False


def _add_photo(light: LightSource, folder: Path) -> None:
    """The photograph's camera, depth mesh and pixels, in the light's room frame (a fit-photo folder)."""
    from roomlight.fitting.insert.fitted import load_fitted_photo
    from roomlight.fitting.photo.geometry import build_geometry

    fitted = load_fitted_photo(folder)
    light.photo = fitted
    case, t = fitted.case, fitted.transform
    geo = build_geometry(case, fitted.config)
    light.objects = [SceneObject("depth_mesh", t.points(geo.mesh.vertices).astype(np.float32),
                                 geo.mesh.faces.astype(np.int32), "shadow_catcher", "photo")]
    k = case.intrinsics
    light.camera = {"origin": t.translation.tolist(), "target": (t.translation + t.forward).tolist(),
                    "up": t.up.tolist(), "fov": k.fov_x, "rotation": t.rotation.tolist(),
                    "intrinsics": k.intrinsics_dict(), "width": k.width,
                    "height": k.height}
    light.backplate = np.ascontiguousarray(case.image, np.float32)
    # The same light `roomlight insert` renders: its surface pushed behind the depth mesh wherever it ran
    # through or in front of it, so the shadow catcher receives the light instead of sharing its place.
    from roomlight.core.emitter.enclose import enclosing_depth

    pts = t.points(geo.mesh.vertices)
    pts = np.concatenate([pts, *[t.points(o.vertices) for o in geo.objects]]) if geo.objects else pts
    depth, moved = enclosing_depth(light.depth, pts)
    if moved > 0:
        light.light = Light(light.light.radiance, depth, "mesh", light.light.frame)
        v, f, uv = _mesh_from_panorama(light.light)
        light.vertices, light.faces, light.uv = v, f.astype(np.int32), uv
    light.metadata["photo_fit"] = {"method": fitted.method, "scale": float(t.scale),
                                   "light_enclosing_scene": {"texels_moved": round(moved, 4)}}
