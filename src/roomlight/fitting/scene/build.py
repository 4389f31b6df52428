"""From a scene description to Mitsuba objects, target images, masks and surface points."""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import numpy as np
import torch

from roomlight.core.color import display_to_linear
from roomlight.errors import RoomlightError
from roomlight.core.render.mesh import mitsuba_mesh
from roomlight.fitting.scene.description import ObjectSpec, SceneError, SceneSpec, ViewSpec, read_scene

__all__ = ["load_scene", "check_scene_files", "object_geometry", "mitsuba_object", "view_objects", "object_points",
           "load_view_target", "scene_points"]


@lru_cache(maxsize=64)
def _mesh_file(path: str, mtime_ns: int) -> tuple[np.ndarray, np.ndarray]:
    """Mesh file contents; cached per (path, modification time) so edits are seen."""
    from roomlight.core.render.variant import mitsuba

    mi = mitsuba()
    kind = "obj" if path.lower().endswith(".obj") else "ply"
    try:
        m = mi.load_dict({"type": kind, "filename": path})
    except Exception as exc:
        raise SceneError(f"{path}: Mitsuba could not read the mesh: {str(exc).splitlines()[0]}") from None
    p = mi.traverse(m)
    v = np.array(p["vertex_positions"], dtype=np.float64).reshape(-1, 3)
    f = np.array(p["faces"], dtype=np.int64).reshape(-1, 3)
    return v, f


def object_geometry(obj: ObjectSpec) -> tuple[np.ndarray, np.ndarray]:
    """World-space (vertices (N, 3) float64 metres, faces (F, 3) int64) of an object."""
    from roomlight.fitting.scene.shapes import builtin_shape

    if obj.shape is not None:
        v, f = builtin_shape(obj.shape)
        v, f = v.astype(np.float64), f.astype(np.int64)
    else:
        v, f = _mesh_file(str(obj.mesh), Path(obj.mesh).stat().st_mtime_ns)
    m = obj.matrix()
    return v @ m[:3, :3].T + m[:3, 3], f


def mitsuba_object(obj: ObjectSpec):
    """A ``mi.Mesh`` of the object, in world space, with its BSDF."""
    v, f = object_geometry(obj)
    return mitsuba_mesh(obj.id, v, f, obj.material.bsdf())


def view_objects(scene: SceneSpec, view: ViewSpec | str) -> dict:
    """Mitsuba objects of a view's objects, keyed by id (to pass to EmitterScene(objects=...))."""
    v = scene.view(view) if isinstance(view, str) else view
    return {oid: mitsuba_object(scene.objects[oid]) for oid in v.objects}


def object_points(obj: ObjectSpec, n: int, seed: int = 0) -> np.ndarray:
    """(n, 3) points sampled uniformly by area on the object's surface (plus its vertices' hull
    extremes are covered as n grows)."""
    v, f = object_geometry(obj)
    a = v[f[:, 1]] - v[f[:, 0]]
    b = v[f[:, 2]] - v[f[:, 0]]
    area = 0.5 * np.linalg.norm(np.cross(a, b), axis=1)
    rng = np.random.default_rng(seed)
    tri = rng.choice(len(f), size=n, p=area / area.sum())
    r1, r2 = rng.random(n), rng.random(n)
    s = np.sqrt(r1)
    return v[f[tri, 0]] * (1 - s)[:, None] + v[f[tri, 1]] * (s * (1 - r2))[:, None] + v[f[tri, 2]] * (s * r2)[:, None]


def scene_points(scene: SceneSpec, ids=None, per_object: int = 512, seed: int = 0) -> torch.Tensor:
    """(M, 3) float32 surface points of the given objects (default: all), for the repulsion term."""
    ids = list(scene.objects) if ids is None else list(ids)
    pts = [object_points(scene.objects[i], per_object, seed + k) for k, i in enumerate(ids)]
    return torch.from_numpy(np.concatenate(pts)).float()


def _read_image(path: Path) -> np.ndarray:
    if path.suffix.lower() == ".exr":
        from roomlight.core.io import read_exr

        ch = read_exr(path)
        if not all(c in ch for c in "RGB"):
            raise SceneError(f"{path}: expected R, G, B channels, found {', '.join(ch)}")
        return np.stack([ch[c] for c in "RGB"], -1).astype(np.float32)
    from PIL import Image

    try:
        img = np.asarray(Image.open(path).convert("RGB"), dtype=np.float32) / 255.0
    except Exception as exc:
        raise SceneError(f"{path}: cannot read the image ({exc})") from None
    # 8-bit images are gamma-2.2 encoded, as the benchmark writes them and as cameras roughly do
    return display_to_linear(img)


def load_view_target(view: ViewSpec, prefer: str = "ldr") -> tuple[torch.Tensor, torch.Tensor]:
    """(image (H, W, 3) linear float32, mask (H, W) bool) of a view.

    ``prefer='ldr'`` uses the 8-bit recording (linearised) when there is one, as the paper's
    fitting does; ``'hdr'`` uses the linear EXR. The mask defaults to all pixels.
    """
    order = [view.ldr, view.image] if prefer == "ldr" else [view.image, view.ldr]
    path = next((p for p in order if p is not None), None)
    if path is None:
        raise SceneError(f"view {view.name!r}: has neither 'image' nor 'ldr'; nothing to fit to")
    img = _read_image(path)
    h, w = img.shape[:2]
    if (w, h) != (view.camera.width, view.camera.height):
        raise SceneError(f"{path}: image is {w}x{h} but view {view.name!r}'s camera is "
                         f"{view.camera.width}x{view.camera.height}")
    if view.mask is not None:
        from PIL import Image

        try:
            m = np.asarray(Image.open(view.mask).convert("L")) > 127
        except Exception as exc:
            raise SceneError(f"{view.mask}: cannot read the mask ({exc})") from None
        if m.shape != (h, w):
            raise SceneError(f"{view.mask}: mask is {m.shape[1]}x{m.shape[0]}, image is {w}x{h}")
    else:
        m = np.ones((h, w), bool)
    return torch.from_numpy(img), torch.from_numpy(m)


def load_scene(path, check_files: bool = True) -> SceneSpec:
    """Read and validate a scene description (``.json``, ``.yaml`` or ``.yml``; or its folder).

    With ``check_files`` (default) every referenced file is also read once, so an unreadable
    panorama, mesh, image or mask is rejected up front with its name.
    """
    scene = read_scene(path)
    if check_files:
        check_scene_files(scene)
    return scene


def check_scene_files(scene: SceneSpec) -> None:
    """Read every file a scene names (emitter panorama, meshes, images, masks), so that a corrupt
    one is reported now, by name, rather than in the middle of a fit."""
    if scene.emitter is not None:
        scene.emitter.load()  # raises InputFileError naming the file
    for obj in scene.objects.values():
        if obj.mesh is not None:
            object_geometry(obj)
    for view in scene.views.values():
        if view.image is not None or view.ldr is not None:
            for prefer in ("ldr", "hdr"):
                try:
                    load_view_target(view, prefer)
                except SceneError:
                    raise
                except RoomlightError as exc:
                    raise SceneError(str(exc)) from None
