"""Virtual probes: spheres inserted on the objects' surfaces to show what a recovered light does there.

A real photograph has no ground-truth illumination, so a recovered light is judged by its
consequences (paper §4.3): mirror and diffuse spheres placed at several positions on the object
surfaces and rendered with the objects. Under an env map every probe shows the same radiance
wherever it stands; a 2.5D light shows each probe the part of the room it faces.

Probe positions are chosen on the visible object surfaces by farthest-point sampling (so they
spread over the scene), each sphere resting on the surface along its normal, with a radius
proportional to its distance from the camera (``probe_size``: all probes look equally large).
Close-ups are rendered from the camera's position, aimed at each probe, with a field of view
that frames it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from roomlight.errors import RoomlightError
from roomlight.core.light import Light
from roomlight.fitting.photo.geometry import SceneTransform
from roomlight.fitting.photo.unproject import ObjectMesh

__all__ = ["ProbeSite", "choose_probe_sites", "LightView", "render_probes", "probe_figure", "PROBE_MATERIALS",
           "closeup_disc", "CLOSEUP_MARGIN"]

#: The probe materials of the figure, by row.
PROBE_MATERIALS = ("mirror", "diffuse")


@dataclass(frozen=True)
class ProbeSite:
    """A probe in the camera frame: sphere centre (metres of the depth map) and radius."""

    center: tuple[float, float, float]
    radius: float
    label: int

    def to_dict(self) -> dict:
        return {"center_camera": [round(c, 6) for c in self.center], "radius_camera": round(self.radius, 6),
                "object": self.label}


def choose_probe_sites(objects: list[ObjectMesh], count: int, size: float, intrinsics=None,
                       border: float = 0.1) -> list[ProbeSite]:
    """``count`` probe sites spread over the objects' surfaces (camera frame).

    Candidates are the objects' vertices (optionally only those projecting at least ``border``
    of the image's size away from its edges); the first site is the candidate nearest the objects'
    centroid, each next one the candidate farthest from the sites so far.
    """
    if count <= 0:
        return []
    verts = np.concatenate([o.vertices for o in objects])
    normals = np.concatenate([o.normals for o in objects])
    labels = np.concatenate([np.full(len(o.vertices), o.label) for o in objects])
    keep = np.ones(len(verts), bool)
    if intrinsics is not None:
        z = -verts[:, 2]
        u = intrinsics.cx + intrinsics.fx * verts[:, 0] / z
        v = intrinsics.cy - intrinsics.fy * verts[:, 1] / z
        bx, by = border * intrinsics.width, border * intrinsics.height
        inside = (u > bx) & (u < intrinsics.width - bx) & (v > by) & (v < intrinsics.height - by)
        if inside.any():
            keep = inside
    verts, normals, labels = verts[keep], normals[keep], labels[keep]
    first = int(np.argmin(np.linalg.norm(verts - verts.mean(0), axis=1)))
    chosen = [first]
    dist = np.linalg.norm(verts - verts[first], axis=1)
    while len(chosen) < min(count, len(verts)):
        nxt = int(np.argmax(dist))
        if dist[nxt] <= 0:
            break
        chosen.append(nxt)
        dist = np.minimum(dist, np.linalg.norm(verts - verts[nxt], axis=1))
    sites = []
    for i in chosen:
        r = size * float(np.linalg.norm(verts[i]))
        c = verts[i] + normals[i] * r * 1.02  # resting on the surface, not inside it
        sites.append(ProbeSite(tuple(float(x) for x in c), r, int(labels[i])))
    return sites


@dataclass
class LightView:
    """A light to show the probes under, in its room frame.

    Attributes:
        name: the row's title (e.g. the method).
        light: the light (radiance (H, 2H, 3) linear, depth (H, 2H) metres or None, ``mesh`` or
            ``envmap``); its frame is camera frame -> its room frame.
        transform: that frame as the fit's parts (rotation, scale, translation), with which the
            objects, probes and camera are placed.
        bsdfs: the objects' BSDF dicts by label.

    Raises:
        RoomlightError: the light's frame is not ``transform``.
    """

    name: str
    light: Light
    transform: SceneTransform
    bsdfs: dict

    def __post_init__(self):
        if not np.allclose(self.light.frame, self.transform.matrix):
            raise RoomlightError(f"probes row {self.name!r}: the light's frame is not its camera-to-room transform")


#: A close-up's half field of view is this times the probe's angular radius.
CLOSEUP_MARGIN = 1.15


def _closeup_sensor(transform: SceneTransform, center_room: np.ndarray, radius_room: float, res: int) -> dict:
    from roomlight.core.render.camera import perspective_sensor

    eye = transform.translation
    d = float(np.linalg.norm(center_room - eye))
    half = math.asin(min(radius_room / d, 0.95)) * CLOSEUP_MARGIN
    return perspective_sensor(eye.tolist(), center_room.tolist(), transform.up.tolist(), math.degrees(2 * half),
                              res, res)


def closeup_disc(site: ProbeSite, resolution: int, shrink: float = 0.9) -> np.ndarray:
    """(res, res) bool: the close-up pixels whose centre ray meets the probe sphere, shrunk to
    ``shrink`` of its angular radius (the rim mixes sphere and background). Scale-free: the
    same in every room frame."""
    d = float(np.linalg.norm(site.center))
    alpha = math.asin(min(site.radius / d, 0.95))
    t = math.tan(alpha * CLOSEUP_MARGIN)
    x = ((np.arange(resolution) + 0.5) / resolution * 2 - 1) * t
    xx, yy = np.meshgrid(x, x)
    return np.arctan(np.hypot(xx, yy)) < shrink * alpha


def render_probes(view: LightView, objects: list[ObjectMesh], sites: list[ProbeSite], intrinsics, spp: int = 64,
                  resolution: int = 64, seed: int = 0, max_depth: int = 4, materials=PROBE_MATERIALS,
                  frame: bool = True) -> dict[str, np.ndarray]:
    """Renders of the probes under one light.

    Returns, for each of ``materials`` (names of :mod:`roomlight.core.render.materials`), an array
    (n, res, res, 3) of close-ups, and with ``frame`` also ``frame``: (H, W, 3) the photograph's
    view with the first material's probes inserted; all linear RGB.
    """
    from roomlight.fitting.photo.scene import object_shapes, photo_sensor
    from roomlight.core.render.materials import material
    from roomlight.core.render.scene import EmitterScene

    t = view.transform
    out: dict[str, np.ndarray] = {}
    for n, mat in enumerate(materials):
        extra = dict(object_shapes(objects, t, view.bsdfs))
        for k, s in enumerate(sites):
            extra[f"probe_{k}"] = {"type": "sphere", "center": t.points(np.asarray(s.center)).tolist(),
                                   "radius": float(s.radius * t.scale), "bsdf": material(mat)}
        sensor = photo_sensor(intrinsics, t) if frame and n == 0 else None
        es = EmitterScene(view.light.kind, tuple(view.light.radiance.shape[:2]), objects=extra, sensor=sensor,
                          integrator={"type": "path", "max_depth": int(max_depth)})
        es.set_emitter(view.light.radiance, view.light.depth)
        if sensor is not None:
            out["frame"] = es.render(spp=spp, seed=seed).numpy()
        shots = []
        for k, s in enumerate(sites):
            cam = es.mi.load_dict(_closeup_sensor(t, t.points(np.asarray(s.center)), s.radius * t.scale, resolution))
            shots.append(es.render(spp=spp, seed=seed + 1 + k, sensor=cam).numpy())
        out[mat] = np.stack(shots) if shots else np.zeros((0, resolution, resolution, 3), np.float32)
    return out


def _to_uint8(linear: np.ndarray) -> np.ndarray:
    from roomlight.core.color import linear_to_srgb

    return np.rint(linear_to_srgb(linear) * 255).astype(np.uint8)


def probe_figure(rows: list[tuple[str, dict[str, np.ndarray]]], path, photo: np.ndarray | None = None) -> None:
    """``probes.png``: one row per light (its title above it): the view with mirror probes, then the
    mirror close-ups, then the diffuse close-ups; the photograph first when given. sRGB, no
    exposure change (the lights are fitted to the photograph's exposure)."""
    from PIL import Image, ImageDraw

    gap, title_h = 4, 14
    panels = []
    for name, renders in rows:
        res = renders["mirror"].shape[1] if len(renders["mirror"]) else 64
        frame = Image.fromarray(_to_uint8(renders["frame"]))
        frame = frame.resize((max(1, round(frame.width * res / frame.height)), res), Image.LANCZOS)
        tiles = [frame] + [Image.fromarray(_to_uint8(x)) for m in PROBE_MATERIALS for x in renders[m]]
        panels.append((name, tiles))
    if photo is not None:
        res = panels[0][1][0].height if panels else 64
        img = Image.fromarray(_to_uint8(photo))
        panels.insert(0, ("photograph", [img.resize((max(1, round(img.width * res / img.height)), res), Image.LANCZOS)]))
    width = max(sum(t.width for t in tiles) + gap * (len(tiles) - 1) for _, tiles in panels)
    height = sum(title_h + tiles[0].height + gap for _, tiles in panels)
    canvas = Image.new("RGB", (width + 2 * gap, height + gap), (24, 24, 24))
    draw = ImageDraw.Draw(canvas)
    y = gap
    for name, tiles in panels:
        label = name if name == "photograph" else (
            f"{name}: view with mirror probes | mirror probes x{(len(tiles) - 1) // 2} | diffuse probes")
        draw.text((gap, y + 1), label, fill=(230, 230, 230))
        y += title_h
        x = gap
        for tile in tiles:
            canvas.paste(tile, (x, y))
            x += tile.width + gap
        y += tiles[0].height + gap
    canvas.save(str(path), format="PNG")
