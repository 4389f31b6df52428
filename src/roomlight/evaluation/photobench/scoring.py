"""Scoring a recovered light on a photo: the probes re-rendered under it against the true probes.

A method returns a :class:`~roomlight.core.light.Light` (a 2.5D area light, an env map or a sphere
proxy: radiance (H, W, 3), depth (H, W) or none, its kind) in its own frame -- centred on the
light's capture point, with the panorama's axes -- and where the photographed scene sits in that
frame: its ``frame``, the similarity p_light = s R p_camera + t from the photo's camera frame
(recorded as ``light_from_camera``; a fit may express the room in other units than the depth
map's metres, hence s). Rendering is unchanged by a uniform
scale of the whole scene, so the probes are rendered in the light's frame:

- the probe spheres (every probe of the photo, centres and radii from ``truth/probes.json``
  mapped into that frame) in each probe material (diffuse, matte, mirror), and the inserted
  objects with their **true** geometry and materials (they shadow and reflect onto the probes
  in the ground truth too, and only the light is scored here);
- the photo's camera, same intrinsics, mapped into that frame; a camera ray that meets a probe
  or an object starts just in front of it, so a light mesh that does not enclose the camera (a
  2.5D light captured low in the room, say) cannot hide what the photo shows;
- Mitsuba ``path`` integrator, :data:`SCORE_MAX_DEPTH`, ``spp`` samples per pixel, seeds other
  than the ground truth's.

**Positions through the methods' depth.** A method sees the scene only through ``depth.exr``; a
user of it would put a probe (or find an object) where that depth says. When the benchmark gives
the methods a degraded depth, every probe and object is therefore moved, about the camera
centre, by the factor between the given and the true depth at the pixel its centre projects to
(``depth.exr / truth/depth.exr``, bilinear; the degradation is a smooth field), and scaled with
it, so it covers the same pixels. With the exact depth the factor is 1. The oracles know the true
geometry and use factor 1.

Only the probe window (``window`` of ``truth/probes.json``) is rendered. Each probe material's
render is compared with ``truth/probes_<material>.exr`` over the probe pixels
(``truth/probe_mask.png``) with the synthetic benchmark's metrics
(:func:`roomlight.evaluation.harness.metrics.score_view`: PSNR LDR, RMSE HDR, RGB angular error), overall and
per probe. Recovered materials are compared per object with the true ones
(:func:`material_errors`).

The **oracle** light is the room captured at the oracle centre (``truth/oracle.exr``, world
axes): shown as a 2.5D area light (``oracle``) or an env map (``oracle-envmap``), it is the
best each representation can do at this resolution.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from roomlight.errors import RoomlightError
from roomlight.core.light import Light, similarity_parts
from roomlight.fitting.photo.camera import PhotoCamera
from roomlight.evaluation.photobench import case as fmt
from roomlight.evaluation.photobench.objects import PROBE_MATERIALS, InsertedObject, PrincipledMaterial, ProbeSphere

__all__ = ["SCORE_MAX_DEPTH", "SCORE_SEED", "MATERIAL_METRICS", "PhotoTruth", "load_truth", "oracle_light",
           "similarity_parts", "render_probes", "score_light", "material_errors"]

#: Longest light path of the scoring renders (the paper's renders: 4).
SCORE_MAX_DEPTH = 4
#: Base seed of the scoring renders (the ground truth's seeds stay below 2^29 + 2^25).
SCORE_SEED = 7_000_001 + (1 << 30)
#: Material errors per object (all lower-is-better): RMSE of the linear RGB albedo, absolute
#: roughness error, absolute metallic error.
MATERIAL_METRICS = ("albedo_rmse", "roughness_error", "metallic_error")


@dataclass
class PhotoTruth:
    """The ground truth of one photo case (world frame, metres)."""

    case_dir: Path
    camera: PhotoCamera
    objects: list[InsertedObject]
    probes: list[ProbeSphere]
    probe_images: dict[str, np.ndarray]        #: material -> (h, w, 3) float32, the probe window
    probe_mask: np.ndarray                     #: (H, W) int32: probe label, 0 elsewhere (whole frame)
    exposure: float
    seeds: dict = field(default_factory=dict)
    depth_factors: dict = field(default_factory=dict)  #: object / probe id -> given / true depth at its centre
    window: tuple = None                       #: (x0, y0, w, h) of the probe images in the frame

    @property
    def window_mask(self) -> np.ndarray:
        """(h, w) int32 probe labels inside the probe window."""
        x0, y0, w, h = self.window
        return self.probe_mask[y0:y0 + h, x0:x0 + w]

    @property
    def materials(self) -> dict[int, PrincipledMaterial]:
        return {o.label: o.material for o in self.objects}


def load_truth(case_dir) -> PhotoTruth:
    """Read a case's ``truth/`` (see :mod:`roomlight.evaluation.photobench.case`)."""
    d = Path(case_dir)
    record = fmt.read_json(d / fmt.RECORD)
    probes = fmt.read_json(d / fmt.PROBES)
    mats = fmt.read_json(d / fmt.MATERIALS)
    objects = sorted((InsertedObject.from_dict(o) for o in mats["objects"].values()), key=lambda o: o.label)
    images = {m: fmt.read_rgb_exr(d / fmt.probe_image_name(m)) for m in probes["materials"]}
    mask = fmt.read_labels(d / fmt.PROBE_MASK)
    camera = fmt.read_camera(d)
    if mask.shape != (camera.height, camera.width):
        raise fmt.PhotoCaseError(f"{d / fmt.PROBE_MASK}: {mask.shape} does not match the camera's "
                                 f"{camera.height}x{camera.width}")
    spheres = [ProbeSphere.from_dict(p) for p in probes["probes"]]
    window = tuple(int(v) for v in probes["window"])
    for m, img in images.items():
        if img.shape[:2] != (window[3], window[2]):
            raise fmt.PhotoCaseError(f"{d / fmt.probe_image_name(m)}: {img.shape[1]}x{img.shape[0]} does not match "
                                     f"the probe window {window[2]}x{window[3]}")
    ratio = fmt.read_depth_exr(d / fmt.DEPTH).astype(np.float64) / fmt.read_depth_exr(d / fmt.TRUE_DEPTH)
    centres = [o.translate for o in objects] + [p.center for p in spheres]
    factors = _sample_map(ratio, camera.project(np.asarray(centres))[0])
    return PhotoTruth(d, camera, objects, spheres, images, mask, float(record["exposure"]),
                      dict(record.get("seeds", {})),
                      {x.id: float(f) for x, f in zip([*objects, *spheres], factors)}, window)


def _sample_map(a: np.ndarray, xy: np.ndarray) -> np.ndarray:
    """Bilinear samples of an (H, W) map at film points (N, 2) (pixel centres at +0.5), clamped to the border."""
    h, w = a.shape
    x = np.clip(xy[:, 0] - 0.5, 0, w - 1)
    y = np.clip(xy[:, 1] - 0.5, 0, h - 1)
    x0, y0 = np.floor(x).astype(int), np.floor(y).astype(int)
    x1, y1 = np.minimum(x0 + 1, w - 1), np.minimum(y0 + 1, h - 1)
    fx, fy = x - x0, y - y0
    return ((1 - fy) * ((1 - fx) * a[y0, x0] + fx * a[y0, x1]) + fy * ((1 - fx) * a[y1, x0] + fx * a[y1, x1]))


def oracle_light(case_dir, kind: str = "mesh", truth: PhotoTruth | None = None) -> Light:
    """The oracle light of a case (``truth/oracle.exr``) as a 2.5D area light or (``kind="envmap"``) an env map."""
    from roomlight.core.io import read_panorama

    d = Path(case_dir)
    truth = truth or load_truth(d)
    pano = read_panorama(d / fmt.ORACLE)
    centre = np.asarray(pano.metadata.get("center"), np.float64)
    if centre.shape != (3,):
        raise fmt.PhotoCaseError(f"{d / fmt.ORACLE}: no oracle centre in its metadata")
    light_from_world = np.eye(4)
    light_from_world[:3, 3] = -centre          # world axes, origin at the oracle centre
    return Light(pano.radiance, None if kind == "envmap" else pano.depth, kind, light_from_world @ truth.camera.matrix)


def _camera_in_light(camera: PhotoCamera, light_from_world: np.ndarray) -> PhotoCamera:
    s, r, _ = similarity_parts(light_from_world, "light frame")
    m = np.eye(4)
    m[:3, :3] = r @ camera.matrix[:3, :3]
    m[:3, 3] = light_from_world[:3, :3] @ camera.origin + light_from_world[:3, 3]
    return PhotoCamera(camera.width, camera.height, camera.fx, camera.fy, camera.cx, camera.cy, m)


def render_probes(truth: PhotoTruth, light: Light, material: str, spp: int = 64, seed: int = SCORE_SEED,
                  max_depth: int = SCORE_MAX_DEPTH, given_depth: bool = True) -> np.ndarray:
    """The photo's camera view of the probes (in ``material``) and the true objects under ``light``,
    in the probe window.

    ``given_depth``: place them through the depth the methods got (module docstring); False for
    the true geometry (the oracles).

    Returns:
        (h, w, 3) float32 linear radiance of the probe window (the photo's exposure, as the
        light's radiance is).
    """
    from roomlight.evaluation.photobench.tracing import trace_image
    from roomlight.core.render.scene import EmitterScene

    world_to_camera = np.linalg.inv(truth.camera.matrix)
    light_from_world = light.seen_from(world_to_camera).frame

    def placed(item_id: str) -> np.ndarray:
        f = truth.depth_factors.get(item_id, 1.0) if given_depth else 1.0
        scale = np.diag([f, f, f, 1.0])  # about the camera centre, in the camera frame
        return light.frame @ scale @ world_to_camera

    shapes = {o.id: o.mitsuba_mesh(placed(o.id)) for o in truth.objects}
    shapes.update({p.id: p.mitsuba_shape(material, placed(p.id)) for p in truth.probes})
    es = EmitterScene(light.kind, tuple(light.radiance.shape[:2]), objects=shapes,
                      integrator={"type": "path", "max_depth": int(max_depth)})
    es.set_emitter(light.radiance, light.depth)
    from roomlight.core.render.variant import mitsuba

    front = mitsuba().load_dict({"type": "scene", **shapes})
    return trace_image(es.scene, _camera_in_light(truth.camera, light_from_world), spp, seed, foreground=front,
                       window=truth.window)


def score_light(truth: PhotoTruth, light: Light, spp: int = 64, seed: int = SCORE_SEED,
                renders: dict | None = None, given_depth: bool = True) -> dict:
    """Scores of ``light`` on every probe material: ``{material: {metrics..., "per_probe": {label: metrics}}}``.

    ``renders``, when given, receives each material's (H, W, 3) render; ``given_depth``: see
    :func:`render_probes`.
    """
    from roomlight.evaluation.harness.metrics import score_view

    out = {}
    for k, m in enumerate(PROBE_MATERIALS):
        img = render_probes(truth, light, m, spp, seed + 7919 * k, given_depth=given_depth)
        if renders is not None:
            renders[m] = img
        gt = truth.probe_images[m]
        mask = truth.window_mask
        scores = score_view(img, gt, mask > 0)
        scores["per_probe"] = {str(p.label): score_view(img, gt, mask == p.label) for p in truth.probes
                               if (mask == p.label).any()}
        out[m] = scores
    return out


def _sphere_points(count: int = 256) -> np.ndarray:
    """(count, 3) unit vectors spread evenly over the sphere (a Fibonacci lattice)."""
    i = np.arange(count) + 0.5
    z = 1.0 - 2.0 * i / count
    r = np.sqrt(1.0 - z * z)
    phi = np.pi * (1.0 + 5.0 ** 0.5) * i
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


def probes_outside(truth: PhotoTruth, light: Light, given_depth: bool = True, points: int = 256) -> dict:
    """Per probe (by label), the share of its surface that the 2.5D ``light`` does not enclose, placed as
    :func:`render_probes` places it; an empty dict for a light without depth (an env map). A probe
    outside the light sees the mesh's back faces, which emit nothing, and renders black."""
    import torch

    from roomlight.fitting.inverse.floor import outside_share

    if light.depth is None:
        return {}
    world_to_camera = np.linalg.inv(truth.camera.matrix)
    unit = _sphere_points(points)
    depth = light.depth.double()
    out = {}
    for p in truth.probes:
        f = truth.depth_factors.get(p.id, 1.0) if given_depth else 1.0
        m = light.frame @ np.diag([f, f, f, 1.0]) @ world_to_camera
        world = np.asarray(p.center, np.float64) + p.radius * unit
        q = world @ m[:3, :3].T + m[:3, 3]
        out[str(p.label)] = outside_share(depth, torch.from_numpy(q))
    return out


def material_errors(truth: dict, recovered: dict) -> dict:
    """Errors of recovered materials against the true ones.

    Args:
        truth: ``{label: PrincipledMaterial}``.
        recovered: ``{label: {"albedo": [r, g, b], "roughness": x, "metallic": y}}`` (labels as
            ints or strings); a missing object is listed under ``missing`` and left out of the means.
    Returns:
        ``{"per_object": {label: {metric: value}}, "mean": {metric: value}, "missing": [labels], "objects": n}``.
    """
    rec = {int(k): v for k, v in (recovered or {}).items()}
    per, missing = {}, []
    for label, t in sorted(truth.items()):
        r = rec.get(int(label))
        if r is None:
            missing.append(int(label))
            continue
        a = np.asarray(r["albedo"], np.float64)
        if a.shape != (3,) or not np.isfinite(a).all():
            raise RoomlightError(f"recovered material of object {label}: albedo must be three finite numbers, got {a}")
        per[str(label)] = {"albedo_rmse": float(np.sqrt(np.mean((a - np.asarray(t.albedo)) ** 2))),
                           "roughness_error": abs(float(r["roughness"]) - t.roughness),
                           "metallic_error": abs(float(r["metallic"]) - t.metallic)}
    mean = {k: float(np.mean([v[k] for v in per.values()])) if per else float("nan") for k in MATERIAL_METRICS}
    return {"per_object": per, "mean": mean, "missing": missing, "objects": len(truth)}
