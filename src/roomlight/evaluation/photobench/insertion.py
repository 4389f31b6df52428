"""Objects inserted into the benchmark's photographs: their full-transport truth and how well a
recovered light composites them (``roomlight insert``'s differential rendering).

**Building** (:func:`stage_inserts`, :func:`render_insert_truth`): each photo gets
``config.inserts`` new objects, at its first probe positions (``insert_placement = "probes"``, where the
reference light is captured around) or spread over its visible surfaces by distance and height
(``"stratified"``, :func:`stage_stratified_inserts`); a built-in shape (blob, knot, torus or
sphere) of the probe's bounding radius, turned about the vertical, resting on the probe's support, with a
principled material drawn like the photo's own objects. The photo's scene with them is path-traced
from the photo's camera twice: with the photo's seed and samples, so that wherever the new objects change
nothing it is the photograph itself, sample for sample (``truth/insert.exr``); and with a seed of its
own at ``insert_spp`` samples per pixel (``truth/insert_clean.exr``), the truth the composites are scored
against. At the photo's own samples the first is as noisy as the composites it would judge: on the original
suite (64 spp) it held the objects' scores under a 29 dB floor where the clean one leaves 39 dB
(docs/results.md). Their coverage labels are ``truth/insert_mask.png``, their description
``truth/insert.json``. Photos built before the clean truth existed have only the first; ``make-photos``
adds the second in place.

**Scoring** (:func:`insertion_scores`): per new object, the composite against the truth in the
object's *region*, its whole pixels dilated by its own projected radius (so the region covers the
object and the shadow it casts next to it): PSNR LDR, SSIM and RMSE HDR of the region; the object
alone (its whole pixels): PSNR LDR and RMSE HDR, the shading error; and the *shadow*, the region
without the object and its silhouette's ring (:func:`shadow_mask`): what the object does to the
scene around it. The region mixes the two, and an error of one can hide in the other.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from roomlight.evaluation.photobench.objects import InsertedObject, ProbeSphere, draw_material

__all__ = ["INSERT_SHAPES", "INSERT_LABEL0", "INSERT_IMAGE", "INSERT_CLEAN", "INSERT_MASK", "INSERT_JSON",
           "stage_inserts", "stage_stratified_inserts", "render_insert_truth", "read_insert_truth",
           "insert_truth_stamp", "insertion_scores", "region_mask", "shadow_mask"]

#: Shapes of the inserted test objects.
INSERT_SHAPES = ("blob", "knot", "torus", "sphere")
#: Labels of the inserted objects in ``insert_mask.png`` start here (the photo's own objects: 1, 2, ...).
INSERT_LABEL0 = 101
INSERT_IMAGE, INSERT_MASK, INSERT_JSON = "insert.exr", "insert_mask.png", "insert.json"
#: The inserted objects' truth path-traced with a seed of its own at ``insert_spp``: what composites are scored against.
INSERT_CLEAN = "insert_clean.exr"
_GAP = 0.002  # the probes' hover above their support (roomlight.evaluation.photobench.staging)


def stage_inserts(probes: list[ProbeSphere], count: int, rng: np.random.Generator, metal_fraction: float = 0.3,
                  roughness=(0.15, 0.8), palette: str = "hsv", metal_colours: str = "as-drawn") -> list[InsertedObject]:
    """``count`` new objects at the first probe positions, each resting on its probe's support (materials
    from :func:`~roomlight.evaluation.photobench.objects.draw_material`)."""
    out = []
    for k, p in enumerate(probes[:count]):
        shape = INSERT_SHAPES[int(rng.integers(len(INSERT_SHAPES)))]
        yaw = float(rng.uniform(0.0, 360.0))
        material = draw_material(rng, metal_fraction, tuple(roughness), palette, metal_colours)
        probe_obj = InsertedObject(f"insert{k + 1}", INSERT_LABEL0 + k, shape, (float(p.radius),), yaw, (0.0, 0.0, 0.0),
                                   material)
        v, _ = probe_obj.local_geometry()
        support_y = p.center[1] - p.radius - _GAP
        translate = (float(p.center[0]), float(support_y + _GAP - v[:, 1].min()), float(p.center[2]))
        out.append(InsertedObject(probe_obj.id, probe_obj.label, shape, probe_obj.size, yaw, translate, material))
    return out


def stage_stratified_inserts(scenes, photo_meshes: dict, camera, count: int, rng: np.random.Generator,
                             occupied: list[tuple[np.ndarray, float]], config) -> tuple[list[InsertedObject], list[str]]:
    """``count`` new objects spread over the photo's visible horizontal surfaces, independently of the
    probes: one per stratum of :data:`~roomlight.evaluation.photobench.config.INSERT_STRATA` while strata
    last: the nearest, middle and farthest third of the resting points by distance from the camera, and
    the raised ones (at least 15 cm above the lowest: a table top, a shelf). Each rests in a free column
    (clear of the photo's objects and of ``occupied`` footprints: the probes'), is sized like a probe at
    its distance and must show ``config.min_pixels`` whole, unoccluded pixels inside the frame.

    Returns:
        (the objects, the stratum of each).
    """
    from roomlight.core.render.raycast import RayCaster
    from roomlight.evaluation.photobench.config import INSERT_STRATA
    from roomlight.evaluation.photobench.staging import free_column, palette, support_points
    from roomlight.evaluation.photobench.tracing import trace_coverage

    caster = RayCaster(scenes.scene(photo_meshes))
    supports = support_points(caster, camera, rows=48)
    if not len(supports):
        return [], []
    dist = np.linalg.norm(supports - camera.origin, axis=1)
    lo, hi = np.percentile(dist, [100 / 3, 200 / 3])
    raised = supports[:, 1] > supports[:, 1].min() + 0.15
    members = {"near": dist <= lo, "middle": (dist > lo) & (dist <= hi), "far": dist > hi, "raised": raised}
    footprints = list(occupied)
    out, strata = [], []
    for stratum in INSERT_STRATA:
        if len(out) == count:
            break
        pool = np.flatnonzero(members[stratum])
        for _ in range(30 if len(pool) else 0):
            p = supports[int(rng.choice(pool))]
            d = float(np.linalg.norm(p - camera.origin))
            radius = float(np.clip(config.probe_size * d, 0.03, 0.2))
            k = len(out)
            obj = InsertedObject(f"insert{k + 1}", INSERT_LABEL0 + k, INSERT_SHAPES[int(rng.integers(len(INSERT_SHAPES)))],
                                 (radius,), float(rng.uniform(0.0, 360.0)), (0.0, 0.0, 0.0),
                                 draw_material(rng, config.metal_fraction, tuple(config.roughness), palette(config), config.metal_colours))
            v, _ = obj.local_geometry()
            rho = float(np.max(np.hypot(v[:, 0], v[:, 2])))
            height = float(v[:, 1].max() - v[:, 1].min())
            xz = p[[0, 2]]
            if any(np.linalg.norm(xz - c) < rho + r + 0.03 for c, r in footprints):
                continue
            if not free_column(caster, xz, float(p[1]), rho, height):
                continue
            placed = InsertedObject(obj.id, obj.label, obj.shape, obj.size, obj.yaw,
                                    (float(p[0]), float(p[1] + _GAP - v[:, 1].min()), float(p[2])), obj.material)
            mesh = placed.mitsuba_mesh()
            others = {o.id: o.mitsuba_mesh() for o in out}  # the ones placed before may hide it
            cov = trace_coverage(scenes.scene({**photo_meshes, **others, obj.id: mesh}), camera, [mesh],
                                 config.supersample)[0]
            border = cov[0].any() or cov[-1].any() or cov[:, 0].any() or cov[:, -1].any()
            if border or int((cov >= 1.0 - 1e-6).sum()) < config.min_pixels:
                continue
            out.append(placed)
            strata.append(stratum)
            footprints.append((xz, rho))
            break
    return out, strata


def render_insert_truth(scenes, photo_meshes: dict, inserts: list[InsertedObject], camera, spp: int, seed: int,
                        supersample: int, exposure: float) -> tuple[np.ndarray, np.ndarray]:
    """(image (H, W, 3) float32 times ``exposure``, labels (H, W) uint8: INSERT_LABEL0 + k where new
    object k covers the whole pixel) of the photo's scene with the new objects."""
    from roomlight.evaluation.photobench.tracing import trace_coverage, trace_image

    meshes = {o.id: o.mitsuba_mesh() for o in inserts}
    scene = scenes.scene({**photo_meshes, **meshes})
    image = trace_image(scene, camera, spp, seed) * exposure
    cov = trace_coverage(scene, camera, list(meshes.values()), supersample)
    labels = np.zeros(cov.shape[1:], np.uint8)
    for k, o in enumerate(inserts):
        labels[cov[k] >= 1.0 - 1e-6] = o.label
    return image.astype(np.float32), labels


def read_insert_truth(truth_dir, clean: bool = True) -> tuple[np.ndarray, np.ndarray, list[InsertedObject]] | None:
    """(image (H, W, 3) float32, labels (H, W) int32, objects) of a photo built with inserted objects, or None.

    ``clean``: the image is the truth scored against (``insert_clean.exr`` where the photo has one, else the
    render with the photo's samples); False: always the render with the photo's samples."""
    from roomlight.core.io import read_exr

    d = Path(truth_dir)
    if not (d / INSERT_JSON).is_file():
        return None
    ch = read_exr(d / (insert_truth_stamp(d)["image"] if clean else INSERT_IMAGE))
    image = np.stack([ch[c] for c in "RGB"], -1).astype(np.float32)
    from PIL import Image

    labels = np.asarray(Image.open(d / INSERT_MASK)).astype(np.int32)
    objects = [InsertedObject.from_dict(o) for o in json.loads((d / INSERT_JSON).read_text())["objects"]]
    return image, labels, objects


def insert_truth_stamp(truth_dir) -> dict | None:
    """Which image the inserted objects are scored against and at how many samples per pixel
    (``{"image": file name, "spp": n}``), or None for a photo without inserted objects. A score is valid
    while the stamp it was made with is the photo's."""
    d = Path(truth_dir)
    if not (d / INSERT_JSON).is_file():
        return None
    clean = json.loads((d / INSERT_JSON).read_text()).get("clean")
    if clean and (d / clean["image"]).is_file():
        return {"image": str(clean["image"]), "spp": int(clean["spp"])}
    return {"image": INSERT_IMAGE, "spp": None}  # the photo's own samples


def region_mask(labels: np.ndarray, label: int) -> np.ndarray:
    """(H, W) bool: object ``label``'s whole pixels dilated by its projected radius (sqrt(area / pi))."""
    obj = labels == label
    area = int(obj.sum())
    if area == 0:
        return obj
    r = max(1, int(math.ceil(math.sqrt(area / math.pi))))
    yy, xx = np.mgrid[-r:r + 1, -r:r + 1]
    disk = (xx * xx + yy * yy) <= r * r
    h, w = obj.shape
    out = np.zeros_like(obj)
    ys, xs = np.nonzero(obj)
    for dy, dx in zip(*np.nonzero(disk)):
        y, x = ys + dy - r, xs + dx - r
        ok = (y >= 0) & (y < h) & (x >= 0) & (x < w)
        out[y[ok], x[ok]] = True
    return out


def shadow_mask(labels: np.ndarray, label: int) -> np.ndarray:
    """(H, W) bool: object ``label``'s region without the object: its whole pixels and the partly
    covered ring around them (one pixel) left out, so what remains is only the scene the object
    shades or lights (its shadow, its reflected light)."""
    obj = labels == label
    grown = obj.copy()
    grown[1:] |= obj[:-1]
    grown[:-1] |= obj[1:]
    grown[:, 1:] |= grown[:, :-1].copy()
    grown[:, :-1] |= grown[:, 1:].copy()
    return region_mask(labels, label) & ~grown & ((labels == 0) | (labels == label))


def insertion_scores(composite: np.ndarray, truth: np.ndarray, labels: np.ndarray, objects: list[InsertedObject],
                     camera_to_world) -> list[dict]:
    """One record per new object: region, object and shadow scores (module docstring) and its distance (m)."""
    import torch

    from roomlight.evaluation.harness.metrics import LDR_GAMMA, score_view
    from roomlight.prior.eval.metrics import ssim

    def ldr(x: np.ndarray) -> torch.Tensor:  # the benchmark's LDR: clipped, gamma 2.2, no exposure change
        return torch.from_numpy(np.clip(np.ascontiguousarray(x, np.float32), 0, 1) ** (1 / LDR_GAMMA)).permute(2, 0, 1)[None]

    eye = np.asarray(camera_to_world, np.float64)[:3, 3]
    out = []
    for o in objects:
        obj = labels == o.label
        if not obj.any():
            out.append({"id": o.id, "label": o.label, "visible": False})
            continue
        region = region_mask(labels, o.label)
        ys, xs = np.nonzero(region)
        y0, y1, x0, x1 = ys.min(), ys.max() + 1, xs.min(), xs.max() + 1
        r = score_view(composite, truth, region)
        s = score_view(composite, truth, obj)
        shade = shadow_mask(labels, o.label)
        sh = score_view(composite, truth, shade) if shade.any() else {"psnr_ldr": float("nan"), "rmse_hdr": float("nan")}
        # SSIM over the region's bounding box (a 7 x 7 window, smaller for tiny regions)
        win = min(7, y1 - y0, x1 - x0)
        win = win if win % 2 else win - 1
        region_ssim = (float(ssim(ldr(composite[y0:y1, x0:x1]), ldr(truth[y0:y1, x0:x1]), window=win, sigma=win / 7 * 1.5)[0])
                       if win >= 3 else float("nan"))
        out.append({"id": o.id, "label": o.label, "visible": True, "shape": o.shape,
                    "distance_m": float(np.linalg.norm(np.asarray(o.translate) - eye)),
                    "region_pixels": int(region.sum()), "object_pixels": int(obj.sum()),
                    "psnr_ldr": r["psnr_ldr"], "rmse_hdr": r["rmse_hdr"], "ssim": region_ssim,
                    "object_psnr_ldr": s["psnr_ldr"], "object_rmse_hdr": s["rmse_hdr"],
                    "shadow_pixels": int(shade.sum()), "shadow_psnr_ldr": sh["psnr_ldr"],
                    "shadow_rmse_hdr": sh["rmse_hdr"]})
    return out


#: The pseudo-method that pastes the new objects lit by a uniform light of the photo's mean colour,
#: with nothing of the scene around them (no shadow, no reflection of the room's surfaces).
NAIVE = "naive-paste"


def naive_light(case_dir, tau: float = 0.99):
    """A uniform env map of the photograph's mean unsaturated colour (the naive paste's light)."""
    from roomlight.core.light import Light
    from roomlight.evaluation.photobench import case as fmt

    img = fmt.read_rgb_exr(Path(case_dir) / fmt.IMAGE)
    keep = img.max(-1) < tau
    colour = (img[keep] if keep.any() else img.reshape(-1, 3)).mean(0)
    return Light(np.broadcast_to(colour.astype(np.float32), (16, 32, 3)), None, "envmap")


def composite_for_light(case_dir, light, materials: dict, objects: list[InsertedObject], camera, preset: str = "fast",
                        overrides: dict | None = None, spp: int = 64, local_scene: bool = True, seed: int = 11,
                        enclose: bool = True, albedo: np.ndarray | None = None, geometry=None) -> np.ndarray:
    """The new objects composited into the photo under ``light`` (a :class:`~roomlight.core.light.Light` whose
    frame is light-from-camera) by ``roomlight insert``'s differential rendering, at the photo's size:
    (H, W, 3) float32 linear.

    Args:
        materials: the local scene's objects' materials by label ({albedo, roughness, metallic}).
        objects: the new objects (world frame); camera: the photo's ``PhotoCamera``.
        albedo: (H, W, 3) the local scene's albedo instead of the estimated one (diagnosis only).
        geometry: the local scene's shape instead of the photograph's depth mesh
            (:class:`~roomlight.fitting.insert.composite.LocalGeometry`, photo camera frame; diagnosis only).
    """
    from roomlight.fitting.insert.composite import composite_objects
    from roomlight.fitting.insert.fitted import FittedPhoto
    from roomlight.fitting.insert.objects import InsertSpec, PlacedObject
    from roomlight.fitting.photo.case import load_photo
    from roomlight.fitting.photo.config import photo_config
    from roomlight.fitting.photo.geometry import SceneTransform

    config = photo_config(preset, **dict(overrides or {}))
    case = load_photo(str(case_dir), min_object_fraction=config.min_object_fraction)
    fitted = FittedPhoto(Path(case_dir), "light", case, config, light, SceneTransform.from_matrix(light.frame),
                         {int(k): dict(v) for k, v in materials.items()})
    world_to_cam = np.linalg.inv(np.asarray(camera.matrix, np.float64))
    placed = []
    for o in objects:
        v, f = o.geometry(world_to_cam)
        centre = v.mean(0)
        placed.append(PlacedObject(InsertSpec(o.shape, at_xyz=tuple(centre.tolist()), scale=2 * o.size[0]), v, f,
                                   o.material.bsdf(), centre, world_to_cam[:3, :3] @ np.array([0.0, 1.0, 0.0]),
                                   2 * float(o.size[0])))
    res = composite_objects(fitted, placed, size=max(case.height, case.width), spp=spp, seed=seed,
                            local_scene=local_scene, enclose=enclose, albedo=albedo, geometry=geometry)
    return res.composite
