"""Rendered photographs with known answers: a photo case made with Mitsuba from a known room light,
known objects and known materials (tests, measurements, and benchmarks of photo fitting).

The room is a panorama (radiance + radial depth) shown as a 2.5D area light around its capture
point; the camera stands at ``origin`` in that room, level or tilted by (pitch, roll). Every pixel
of the case comes from Mitsuba: the image (path tracing), the depth (the distance of the first
hit along the pixel's centre ray, objects and room alike), the object labels (which object that
ray hits) and the normals (the hit's shading normal, in the camera frame).

Besides the photo case files, ``truth/`` holds what a fit should find: ``panorama.exr`` (the room
light), ``truth.json`` (the camera's pose in the room and every object's material) and
``objects/<label>.ply`` (the objects in the room frame).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch

from roomlight.errors import RoomlightError
from roomlight.fitting.photo.camera import PhotoCamera, camera_rotation
from roomlight.fitting.photo.geometry import SceneTransform
from roomlight.core.render.materials import principled_bsdf
from roomlight.core.render.mesh import mitsuba_mesh

__all__ = ["SyntheticObject", "render_photo", "render_photo_case", "read_truth", "example_photo_case",
           "EXAMPLE_OBJECTS"]


@dataclass
class SyntheticObject:
    """An object of a rendered photograph, in the room frame.

    Attributes:
        label: its mask label (> 0).
        vertices: (N, 3) metres; faces: (F, 3) outward-facing triangles.
        albedo, roughness, metallic: its principled material.
    """

    label: int
    vertices: np.ndarray
    faces: np.ndarray
    albedo: tuple[float, float, float] = (0.5, 0.5, 0.5)
    roughness: float = 0.5
    metallic: float = 0.0

    def bsdf(self) -> dict:
        return principled_bsdf(self.albedo, self.roughness, self.metallic)

    def material(self) -> dict:
        return {"albedo": [float(a) for a in self.albedo], "roughness": float(self.roughness),
                "metallic": float(self.metallic)}


def render_photo(radiance: torch.Tensor, depth: torch.Tensor, objects: list[SyntheticObject], intrinsics: PhotoCamera,
                 origin=(0.0, 0.0, 0.0), pitch_deg: float = 0.0, roll_deg: float = 0.0, spp: int = 256,
                 seed: int = 0, max_depth: int = 4) -> dict[str, np.ndarray]:
    """Render a photograph of ``objects`` lit by the room (radiance (H, W, 3), radial depth (H, W)).

    Returns ``image`` (h, w, 3) linear, ``depth`` (h, w) radial metres from the camera, ``labels``
    (h, w) int32 and ``normals`` (h, w, 3) camera frame, for the intrinsics' image size.
    """
    from roomlight.fitting.photo.scene import photo_sensor
    from roomlight.core.render.scene import EmitterScene
    from roomlight.core.render.variant import mitsuba

    if any(o.label <= 0 for o in objects) or len({o.label for o in objects}) != len(objects):
        raise RoomlightError("rendered photo: object labels must be distinct and > 0")
    transform = SceneTransform(camera_rotation(pitch_deg, roll_deg), 1.0, np.asarray(origin, dtype=np.float64))
    sensor = photo_sensor(intrinsics, transform)
    mi = mitsuba()
    es = EmitterScene("mesh", tuple(radiance.shape[:2]), sensor=sensor,
                      objects={f"object_{o.label}": mitsuba_mesh(f"object_{o.label}", o.vertices, o.faces, o.bsdf())
                               for o in objects},
                      integrator={"type": "path", "max_depth": int(max_depth)})
    es.set_emitter(radiance, depth)
    image = es.render(spp=spp, seed=seed).numpy()

    # One ray through every pixel centre: depth, labels and normals of the first hit.
    h, w = intrinsics.height, intrinsics.width
    rays_cam = intrinsics.pixel_rays().reshape(-1, 3)
    rays_cam /= np.linalg.norm(rays_cam, axis=1, keepdims=True)
    d = transform.directions(rays_cam).astype(np.float32)
    o = np.broadcast_to(transform.translation.astype(np.float32), d.shape)
    ray = mi.Ray3f(mi.Point3f(o[:, 0], o[:, 1], o[:, 2]), mi.Vector3f(d[:, 0], d[:, 1], d[:, 2]))
    si = es.scene.ray_intersect(ray)
    valid = np.array(si.is_valid())
    if not valid.all():
        raise RoomlightError(f"rendered photo: {int((~valid).sum())} pixel ray(s) escape the room; put the camera "
                             "inside the room light")
    dist = np.array(si.t, dtype=np.float64).reshape(h, w)
    labels = np.zeros(h * w, np.int32)
    shapes = {s.id(): s for s in es.scene.shapes()}
    for obj in objects:
        hit = np.array(si.shape == mi.ShapePtr(shapes[f"object_{obj.label}"]), dtype=bool)
        labels[hit] = obj.label
    n_room = np.stack([np.array(si.sh_frame.n.x), np.array(si.sh_frame.n.y), np.array(si.sh_frame.n.z)], -1)
    n_cam = n_room @ transform.rotation  # room -> camera: R^T n
    facing = np.einsum("ij,ij->i", n_cam, -rays_cam) < 0
    n_cam[facing] = -n_cam[facing]
    return {"image": image.astype(np.float32), "depth": dist.astype(np.float32), "labels": labels.reshape(h, w),
            "normals": n_cam.reshape(h, w, 3).astype(np.float32)}


def _scaled_to_key(shot: dict, radiance: torch.Tensor, key: float) -> tuple[dict, torch.Tensor]:
    """Scale the light (and, rendering being linear in it, the image) so the objects' median is ``key``."""
    inside = shot["labels"] > 0
    level = float(np.median(shot["image"][inside].mean(-1))) if inside.any() else float(np.median(shot["image"]))
    f = key / max(level, 1e-8)
    return {**shot, "image": (shot["image"] * f).astype(np.float32)}, radiance * f


def render_photo_case(folder, radiance: torch.Tensor, depth: torch.Tensor, objects: list[SyntheticObject],
                      intrinsics: PhotoCamera, origin=(0.0, 0.0, 0.0), pitch_deg: float = 0.0, roll_deg: float = 0.0,
                      spp: int = 256, seed: int = 0, depth_kind: str = "radial",
                      object_key: float | None = None) -> dict[str, Path]:
    """Render a photograph (:func:`render_photo`) and write it as a photo case folder with ``truth/``.

    ``depth_kind`` ``z`` stores the z-depth instead of the radial distance (camera.json says which).
    ``object_key``: scale the room's radiance (written to ``truth/``) so that the objects' median
    pixel value is this (a camera's exposure); None keeps the radiance as given.
    """
    from roomlight.core.io import write_panorama, write_ply
    from roomlight.fitting.photo.case import write_photo_case
    from roomlight.fitting.photo.unproject import unproject

    shot = render_photo(radiance, depth, objects, intrinsics, origin, pitch_deg, roll_deg, spp, seed)
    if object_key is not None:
        shot, radiance = _scaled_to_key(shot, radiance, object_key)
    d = shot["depth"]
    if depth_kind == "z":
        unit = unproject(np.ones_like(d), intrinsics, "radial")  # unit rays: z of a radial distance of 1
        d = (d * -unit[..., 2]).astype(np.float32)
    folder = Path(folder)
    paths = write_photo_case(folder, shot["image"], d, shot["labels"], intrinsics, depth_kind=depth_kind,
                             normals=shot["normals"], pitch_deg=pitch_deg, roll_deg=roll_deg)
    truth = folder / "truth"
    (truth / "objects").mkdir(parents=True, exist_ok=True)
    write_panorama(truth / "panorama.exr", (radiance.detach().cpu().numpy(), depth.detach().cpu().numpy()), half=False,
                   metadata={"source": "roomlight photo case truth"})
    for obj in objects:
        write_ply(truth / "objects" / f"{obj.label}.ply", obj.vertices, obj.faces)
    info = {"camera": {"origin": [float(x) for x in origin], "pitch_deg": pitch_deg, "roll_deg": roll_deg},
            "materials": {str(o.label): o.material() for o in objects}, "emitter": "panorama.exr",
            "render": {"spp": spp, "seed": seed, "integrator": "path", "max_depth": 4}}
    (truth / "truth.json").write_text(json.dumps(info, indent=2))
    paths["truth"] = truth
    return paths


def read_truth(folder) -> dict:
    """The ``truth/`` of a rendered photo case: ``radiance`` (H, W, 3) and ``depth`` (H, W) tensors,
    ``transform`` (camera frame -> that room, scale 1) and ``materials`` by label."""
    from roomlight.core.io import read_panorama

    truth = Path(folder) / "truth"
    info = json.loads((truth / "truth.json").read_text())
    pano = read_panorama(truth / info["emitter"])  # as written: no exposure calibration on read
    cam = info["camera"]
    transform = SceneTransform(camera_rotation(cam["pitch_deg"], cam["roll_deg"]), 1.0, np.asarray(cam["origin"]))
    return {"radiance": torch.as_tensor(np.asarray(pano.radiance, np.float32)),
            "depth": torch.as_tensor(np.asarray(pano.depth, np.float32)), "transform": transform,
            "materials": {int(k): v for k, v in info["materials"].items()}}


#: The example photograph's objects: (label, built-in shape, bounding radius m, centre in the room, albedo,
#: roughness, metallic). They rest on the example room's floor (y = -1.5 m) in front of the camera.
EXAMPLE_OBJECTS = (
    (1, "sphere", 0.28, (-0.55, -1.22, -2.1), (0.75, 0.32, 0.22), 0.6, 0.0),
    (2, "blob", 0.32, (0.55, -1.2, -2.6), (0.25, 0.45, 0.7), 0.4, 0.0),
    (3, "torus", 0.22, (0.05, -1.42, -1.55), (0.8, 0.8, 0.75), 0.3, 0.0),
)


def example_photo_case(folder, width: int = 320, height: int = 240, fov_deg: float = 60.0, pitch_deg: float = -30.0,
                       panorama_height: int = 128, spp: int = 256, seed: int = 0, depth_kind: str = "z",
                       key: float = 0.35) -> dict[str, Path]:
    """A rendered photo case of three objects on the floor of the example room (needs no data files).

    The camera stands at the room's capture point, 1.5 m above the floor, looking down by
    ``-pitch_deg``; the light is the example room (:func:`roomlight.core.examples.example_room`) as a
    2.5D area light, its radiance scaled so the objects' median pixel is ``key``.
    """
    from roomlight.core.examples import example_room
    from roomlight.fitting.scene.shapes import builtin_shape

    radiance, depth = example_room(panorama_height)
    objects = []
    for label, shape, radius, centre, albedo, rough, metal in EXAMPLE_OBJECTS:
        v, f = builtin_shape(shape)
        objects.append(SyntheticObject(label, v.astype(np.float64) * radius + np.asarray(centre), f.astype(np.int64),
                                       albedo, rough, metal))
    intr = PhotoCamera.from_fov(fov_deg, width, height)
    return render_photo_case(folder, radiance, depth, objects, intr, pitch_deg=pitch_deg, spp=spp, seed=seed,
                             depth_kind=depth_kind, object_key=key)
