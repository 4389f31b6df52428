"""Why the room's own light composites inserted objects the way it does: one factor at a time.

On a photo benchmark built with inserted objects (``roomlight bench make-photos``), every object is
composited under each light and each variant of the pipeline, and scored three ways against its
path-traced truth: the region (object and surroundings), the object's own pixels, and its shadow (the
region without the object). Paired per object and again per photo (a photo's objects share its fitted
light, so only the second resamples independent draws), each factor's effect is printed with a 95 %
bootstrap interval, and every score's noise floor beside it:

- the truth: the suite's clean insertion truth where it has one (``make-photos --insert-spp``), else the
  render with the photo's own samples;
- ``truth noise``: a perfect differential render at the composites' samples (against a clean truth) or the
  truth rendered again with another seed (against the photo-sampled one); the best score any composite can
  reach at those samples;
- ``composite noise``: the same composite with another seed;
- lights: the room's own panorama as a 2.5D light (``oracle``) and at infinity (``oracle-envmap``), and
  any fitted light of a results folder (``--results DIR``: its ``recovered.exr`` and fitted materials);
  where the folder has ``prior-ceiling`` (the prior's best latent for the whole true room), that room as a
  2.5D light and at infinity: what the prior itself can give the 2.5D light, whatever the fit;
- ``enclose``: the light's surface pushed behind the local scene (roomlight.core.emitter.enclose), or
  left where it is (the pipeline before that fix);
- ``spp``: the composite's samples per pixel; ``--truth-spp N``: every score against the truth rendered
  again at N samples (the truth noise then a perfect differential render at the composites' samples);
- ``true albedo`` (``--albedo``): the local scene's albedo taken from the room itself (each pixel's
  surface's diffuse reflectance, 4 × 4 rays per pixel) instead of estimated from the photograph under the
  light (procedural rooms only);
- ``true geometry`` (``--geometry``): the local scene's shape taken from the room itself instead of the
  photograph's depth mesh: the room's triangles cut to the camera's view (what the photograph hides behind
  its surfaces included: the floor under a table, the backs of the objects), the photograph's objects as
  their own closed meshes; the albedo estimated as usual and laid on them through the photograph
  (roomlight.fitting.insert.view_mesh; procedural rooms only);
- ``true level`` (``--level``): each fitted light scaled, channel by channel, by the factor that gives its
  diffuse probes (the results folder's ``probes_diffuse.exr``) the true mean radiance: the light's level
  and colour made right, its shape left as fitted. Paired with the fitted light at infinity scaled the
  same way, it says what the 2.5D shape is worth once the level is right;
- ``reference albedo`` (``--reference``): each fitted light set to the level at which one of the photo's
  own objects (the first dielectric one) has its true mean albedo, the fitted albedos moved against it
  (``roomlight insert --reference-albedo``, as a user who knows one surface's reflectance would).
- ``true depth`` / ``true radiance`` (``--true-depth``): the fitted prior's light with its shape, its
  radiance or both replaced by the true room's as seen from the light's own centre (each texel's depth the
  distance to the room along its direction, its radiance the room's there), and each radiance at
  infinity: a two-by-two of radiance and shape that says which of the fitted room's errors loses the 2.5D
  light's lead over infinity — its shape, or where its light is (procedural rooms only).

Run: .venv/bin/python benchmarks/insertion_diagnosis.py BENCH [--results DIR] [--photos N] [--spp 64]
         [--hi-spp 256] [--truth-spp N] [--quick] [--albedo] [--geometry] [--level] [--reference]
         [--true-depth] [--out FILE.json]
Resumable: each photo's records are kept in ``--out`` as they are made.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

from roomlight.core.stats import bootstrap_mean_interval, bootstrap_slope_interval

SCORES = ("psnr_ldr", "object_psnr_ldr", "shadow_psnr_ldr")


def photo_room(case_dir: Path, truth):
    """(record, the room's scenes, the photo's objects as meshes) of a photo built in a procedural room (as
    built: repainted or not), or None for a set under a captured panorama."""
    from roomlight.evaluation.photobench import case as fmt
    from roomlight.evaluation.photobench.builder import room_of_record
    from roomlight.evaluation.photobench.roomscene import RoomScenes

    record = json.loads((case_dir / fmt.RECORD).read_text())
    room = room_of_record(record)
    if room is None:
        return None
    return record, RoomScenes(room, int(record["config"]["max_depth"])), {o.id: o.mitsuba_mesh() for o in truth.objects}


def truth_noise(case_dir: Path, truth, seed_offset: int = 1000, spp: int | None = None):
    """A perfect differential render with other samples: the photo plus (truth - photo) both rendered
    again with another seed (at ``spp``, default the photo's own), and the new objects' own pixels from that
    truth. Scored against the truth, it is the noise floor of every score (procedural rooms only: None for
    a captured-light photo)."""
    from roomlight.evaluation.photobench import case as fmt
    from roomlight.evaluation.photobench.insertion import read_insert_truth, render_insert_truth
    from roomlight.evaluation.photobench.tracing import trace_image

    built = photo_room(case_dir, truth)
    if built is None:
        return None
    record, scenes, meshes = built
    _, _, inserts = read_insert_truth(case_dir / fmt.TRUTH)
    spp = int(spp or record["config"]["spp"])
    seed, k = int(record["seeds"]["photo"]) + seed_offset, float(record["exposure"])
    again, labels = render_insert_truth(scenes, meshes, inserts, truth.camera, spp, seed,
                                        int(record["config"]["supersample"]), k)
    photo_again = trace_image(scenes.scene(meshes), truth.camera, spp, seed) * k
    photo = fmt.read_rgb_exr(case_dir / fmt.IMAGE)
    return np.where(labels[..., None] > 0, again, photo + (again - photo_again)).astype(np.float32)


def clean_truth(case_dir: Path, truth, spp: int, seed_offset: int = 2000):
    """(H, W, 3) the photograph with its inserted objects path-traced again at ``spp`` samples per pixel
    (another seed), to score against where the benchmark's own truth (the photo's samples) is too noisy to
    tell composites apart; None for a captured-light photo."""
    from roomlight.evaluation.photobench import case as fmt
    from roomlight.evaluation.photobench.insertion import read_insert_truth, render_insert_truth

    built = photo_room(case_dir, truth)
    if built is None:
        return None
    record, scenes, meshes = built
    _, labels, inserts = read_insert_truth(case_dir / fmt.TRUTH)
    image, again = render_insert_truth(scenes, meshes, inserts, truth.camera, spp,
                                       int(record["seeds"]["photo"]) + seed_offset,
                                       int(record["config"]["supersample"]), float(record["exposure"]))
    if not np.array_equal(again, labels):
        raise RuntimeError(f"{case_dir.name}: the objects rendered again cover other pixels than the truth's")
    return image


def true_albedo(case_dir: Path, truth, supersample: int = 4):
    """(H, W, 3) the diffuse reflectance of the surface each pixel of the photograph sees (its room and
    its objects; ``supersample``² rays per pixel on a regular grid), or None for a captured-light photo."""
    import drjit as dr

    from roomlight.core.render.variant import mitsuba
    from roomlight.evaluation.photobench.tracing import camera_rays

    built = photo_room(case_dir, truth)
    if built is None:
        return None
    _, scenes, meshes = built
    scene = scenes.scene(meshes)
    mi, cam, s = mitsuba(), truth.camera, supersample
    jj, ii = np.meshgrid(np.arange(cam.width * s), np.arange(cam.height * s))
    x, y = (jj.ravel() + 0.5) / s, (ii.ravel() + 0.5) / s
    si = scene.ray_intersect(camera_rays(mi, dr, cam, mi.Float(x), mi.Float(y)))
    rho = mi.Color3f(si.bsdf().eval_diffuse_reflectance(si, si.is_valid()))
    rgb = np.stack([np.asarray(rho[c], np.float32) for c in range(3)], -1)
    rgb[~np.asarray(si.is_valid())] = 0.0
    return rgb.reshape(cam.height, s, cam.width, s, 3).mean((1, 3))


def true_geometry(case_dir: Path, truth, max_edge_px: float = 2.0):
    """The room's own shape as a local scene (:class:`~roomlight.fitting.insert.composite.LocalGeometry`, the
    photo's camera frame): every triangle of the room cut to the camera's view and split to ``max_edge_px``
    pixels of the photograph, textured by projection into it; the photograph's objects whole, shaded flat
    as the truth renders them. None for a captured-light photo."""
    from roomlight.core.render.variant import mitsuba
    from roomlight.fitting.insert.composite import LocalGeometry
    from roomlight.fitting.insert.view_mesh import mesh_in_view

    built = photo_room(case_dir, truth)
    if built is None:
        return None
    _, scenes, _ = built
    mi, cam = mitsuba(), truth.camera
    m = cam.matrix

    def to_camera(p):                         # world -> camera frame: q = R^T (p - o)
        return (np.asarray(p, np.float64) - m[:3, 3]) @ m[:3, :3]

    vs, fs, n = [], [], 0
    for shape in scenes.base.shapes():
        if not shape.is_mesh():
            raise RuntimeError(f"{case_dir.name}: room shape {shape.id()} is not a triangle mesh")
        params = mi.traverse(shape)
        v = np.asarray(params["vertex_positions"], np.float64).reshape(-1, 3)
        vs.append(to_camera(v))
        fs.append(np.asarray(params["faces"], np.int64).reshape(-1, 3) + n)
        n += len(v)
    v, f, uv = mesh_in_view(np.concatenate(vs), np.concatenate(fs), cam, max_edge_px)
    world_to_cam = np.linalg.inv(m)
    objects = {int(o.label): (*o.geometry(world_to_cam), None) for o in truth.objects}
    return LocalGeometry(v, f, uv, objects)


def fitted_light(results: Path, photo: str, method: str):
    """(light, materials) of a fitted case of a results folder (materials None where it fitted none), or
    None."""
    from roomlight.core.io import read_panorama
    from roomlight.core.light import Light

    cdir = results / "cases" / photo / method
    if not (cdir / "recovered.exr").is_file():
        return None
    pano = read_panorama(cdir / "recovered.exr")
    meta = pano.metadata
    light = Light(pano.radiance, pano.depth if meta["emitter_kind"] == "mesh" else None, meta["emitter_kind"],
                  np.asarray(meta["light_from_camera"], np.float64))
    if not (cdir / "fit" / "materials.json").is_file():
        return light, None                    # a reference that fits no materials (prior-ceiling)
    mats = json.loads((cdir / "fit" / "materials.json").read_text())
    entries = mats["objects"] if isinstance(mats, dict) else mats
    materials = {int(e["label"]): {"albedo": e["albedo"], "roughness": e["roughness"], "metallic": e["metallic"]}
                 for e in entries}
    return light, materials


def level_factors(results: Path, photo: str, method: str, truth) -> np.ndarray:
    """(3,) per channel: the true diffuse probes' mean radiance over the fitted light's (its probe render in
    the results folder), inside the probe window. A probe render is linear in the light, so the light
    scaled by these factors gives its diffuse probes the true mean colour and level."""
    from roomlight.core.io import read_exr

    channels = read_exr(results / "cases" / photo / method / "probes_diffuse.exr")
    fitted = np.stack([channels[c] for c in "RGB"], -1)
    inside = truth.window_mask > 0
    true = truth.probe_images["diffuse"][inside].mean(0)
    return (true / np.maximum(fitted[inside].mean(0), 1e-12)).astype(np.float32)


def reference_gain(materials: dict, truth) -> float | None:
    """What the light is multiplied by so that the photo's first dielectric object (lowest label, true
    metallic < 0.5) has its true mean albedo, or None when it has none: fitted / true mean albedo."""
    for label in sorted(truth.materials):
        true = truth.materials[label].to_dict()
        if float(true.get("metallic", 0.0)) < 0.5 and int(label) in materials:
            return float(np.mean(materials[int(label)]["albedo"])) / max(float(np.mean(true["albedo"])), 1e-6)
    return None


def room_from_light_centre(case_dir: Path, truth, light, oracle_seed: int = 7):
    """The true room as seen from a 2.5D light's own centre, texel by texel of the light's panorama: the
    depth (light units) of the room's first surface along each texel's direction (a ray cast in the room
    without the photo's objects; a ray that leaves the room keeps the light's own depth) and the radiance
    the room sends to the light's centre from there (the room path-traced as the oracle panorama is, from
    that centre). None for a captured-light photo (no room to cast in) or a light with no depth.

    Returns:
        (radiance (H, 2H, 3), depth (H, 2H)) float32, in the light's frame and units.
    """
    import torch

    from roomlight.core.geometry.equirect import pixel_directions, sample_equirect
    from roomlight.core.light import similarity_parts
    from roomlight.core.render.variant import mitsuba
    from roomlight.datagen.synth.camera import render_radiance
    from roomlight.evaluation.photobench import case as fmt

    built = photo_room(case_dir, truth)
    if built is None or light.kind != "mesh":
        return None
    _, scenes, _ = built
    mi = mitsuba()
    s, r, t = similarity_parts(light.frame)          # p_light = s R p_camera + t
    depth = light.depth.numpy()
    d_light = pixel_directions(*depth.shape).numpy().reshape(-1, 3).astype(np.float64)
    m = truth.camera.matrix                          # camera -> world
    d_world = (d_light @ r) @ m[:3, :3].T            # R^T d, then into the world
    centre = m[:3, :3] @ (-(r.T @ t) / s) + m[:3, 3]
    o = np.broadcast_to(centre, d_world.shape)
    ray = mi.Ray3f(mi.Point3f(*[mi.Float(o[:, k].astype(np.float32)) for k in range(3)]),
                   mi.Vector3f(*[mi.Float(d_world[:, k].astype(np.float32)) for k in range(3)]))
    si = scenes.base.ray_intersect(ray)
    dist = np.asarray(si.t, np.float64)
    hit = np.asarray(si.is_valid(), bool) & np.isfinite(dist)
    true_depth = np.where(hit, s * dist, depth.reshape(-1))
    # the room's radiance path-traced from the light's own centre (world axes, twice the light's
    # resolution, the oracle's samples and exposure), then read in each texel's direction
    record = json.loads((case_dir / fmt.RECORD).read_text())
    height = 2 * depth.shape[0]
    pano = render_radiance(scenes.base, centre, height=height, spp=int(record["config"].get("oracle_spp", 256)),
                           seed=oracle_seed) * float(record["exposure"])
    looked = sample_equirect(torch.as_tensor(pano, dtype=torch.float32).permute(2, 0, 1)[None],
                             torch.as_tensor(d_world, dtype=torch.float32))
    radiance = looked[0].numpy().T
    shape = depth.shape
    return radiance.reshape(*shape, 3).astype(np.float32), true_depth.reshape(shape).astype(np.float32)


def scaled_light(light, factors: np.ndarray):
    """The same light with its radiance multiplied by ``factors`` (3,), per channel."""
    from roomlight.core.light import Light

    return Light(light.radiance * torch_tensor(factors), light.depth, light.kind, light.frame)


def torch_tensor(x: np.ndarray):
    import torch

    return torch.as_tensor(np.asarray(x, np.float32))


def diagnose_photo(case_dir: Path, results: list[Path], spp: int, hi_spp: int, quick: bool = False,
                   albedo: bool = False, geometry: bool = False, truth_spp: int = 0,
                   level: bool = False, reference: bool = False, true_depth: bool = False) -> list[dict]:
    from roomlight.evaluation.photobench import case as fmt
    from roomlight.evaluation.photobench.insertion import (composite_for_light, insert_truth_stamp, insertion_scores,
                                                           read_insert_truth)
    from roomlight.core.light import Light
    from roomlight.evaluation.photobench.scoring import load_truth, oracle_light
    from roomlight.fitting.insert.fitted import albedos_divided

    truth = load_truth(case_dir)
    image, labels, objects = read_insert_truth(case_dir / fmt.TRUTH)
    strata = json.loads((case_dir / fmt.TRUTH / "insert.json").read_text()).get("strata", {})
    true_mats = {k: m.to_dict() for k, m in truth.materials.items()}
    out = []
    if truth_spp:
        image = clean_truth(case_dir, truth, truth_spp)
        if image is None:                     # a captured-light photo: no room to render again
            return out

    def add(name: str, composite: np.ndarray, reference: np.ndarray = image):
        for r in insertion_scores(composite, reference, labels, objects, truth.camera.matrix):
            if r.get("visible"):
                out.append({"photo": case_dir.name, "variant": name, "stratum": strata.get(r["id"]),
                            **{k: r[k] for k in ("id", "distance_m", *SCORES, "region_pixels", "object_pixels",
                                                 "shadow_pixels")}})

    clean_in_suite = insert_truth_stamp(case_dir / fmt.TRUTH)["spp"] is not None
    again = truth_noise(case_dir, truth, spp=spp if (truth_spp or clean_in_suite) else None)
    if again is not None:
        add("truth noise", again)
    lights = {"oracle": (oracle_light(case_dir, "mesh", truth), true_mats),
              "oracle-envmap": (oracle_light(case_dir, "envmap", truth), true_mats)}
    for res in results:
        for method in ("prior", "prior-envmap", "prior-ceiling"):
            got = fitted_light(res, case_dir.name, method)
            if got is not None:
                got = (got[0], got[1] if got[1] is not None else true_mats)
                lights[f"{method} ({res.name})"] = got
                if method == "prior-ceiling":     # the prior's best room, and the same room at infinity
                    room = got[0]
                    lights[f"{method} ({res.name}) at infinity"] = (Light(room.radiance, None, "envmap", room.frame),
                                                                    got[1])
                seen = room_from_light_centre(case_dir, truth, got[0]) if true_depth and method == "prior" else None
                if seen is not None:                   # radiance and shape, fitted or true, crossed
                    fitted, frame, key = got[0], got[0].frame, f"{method} ({res.name})"
                    lights[f"{key} at infinity"] = (Light(fitted.radiance, None, "envmap", frame), got[1])
                    lights[f"{key} true depth"] = (Light(fitted.radiance, seen[1], "mesh", frame), got[1])
                    lights[f"{key} true radiance"] = (Light(seen[0], fitted.depth, "mesh", frame), got[1])
                    lights[f"{key} true radiance true depth"] = (Light(seen[0], seen[1], "mesh", frame), got[1])
                    lights[f"{key} true radiance at infinity"] = (Light(seen[0], None, "envmap", frame), got[1])
                if level and method != "prior-ceiling":
                    factors = level_factors(res, case_dir.name, method, truth)
                    lights[f"{method} ({res.name}) true level"] = (scaled_light(got[0], factors), got[1])
                gain = reference_gain(got[1], truth) if reference and method != "prior-ceiling" else None
                if gain is not None:
                    lights[f"{method} ({res.name}) reference albedo"] = (scaled_light(got[0], np.full(3, gain)),
                                                                         albedos_divided(got[1], gain))
    rho = true_albedo(case_dir, truth) if albedo else None
    shape = true_geometry(case_dir, truth) if geometry else None
    for name, (light, mats) in lights.items():
        variants = [("", dict(enclose=True, spp=spp))]
        if rho is not None:
            variants.append((" true albedo", dict(enclose=True, spp=spp, albedo=rho)))
        if shape is not None:
            variants.append((" true geometry", dict(enclose=True, spp=spp, geometry=shape)))
        if quick:
            pass
        elif light.kind == "mesh":
            variants.append((" unenclosed", dict(enclose=False, spp=spp)))
        if name.startswith("oracle") and not quick:
            variants += [(" seed 2", dict(enclose=True, spp=spp, seed=12)),
                         (f" {hi_spp} spp", dict(enclose=True, spp=hi_spp))]
        for suffix, kw in variants:
            add(name + suffix, composite_for_light(case_dir, light, mats, objects, truth.camera, **kw))
    return out


def paired(records: list[dict], a: str, b: str, key: str, reps: int = 2000, seed: int = 0, by_photo: bool = False):
    """Mean of a - b over the objects both score, 95 % bootstrap interval, wins, count.

    ``by_photo``: each photo's objects' differences averaged first, and the interval, wins and count over
    photos (a photo's objects share its fitted light: they are not independent draws)."""
    ka = {(r["photo"], r["id"]): r[key] for r in records if r["variant"] == a}
    kb = {(r["photo"], r["id"]): r[key] for r in records if r["variant"] == b}
    shared = [k for k in ka if k in kb and math.isfinite(ka[k]) and math.isfinite(kb[k])]
    if by_photo:
        groups: dict[str, list[float]] = {}
        for k in shared:
            groups.setdefault(k[0], []).append(ka[k] - kb[k])
        d = np.array([np.mean(g) for g in groups.values()])
    else:
        d = np.array([ka[k] - kb[k] for k in shared])
    if not len(d):
        return None
    # 2000 resamples, seed 0: the documented diagnosis tables were made with these
    lo, hi = bootstrap_mean_interval(d, resamples=reps, seed=seed)
    return float(d.mean()), lo, hi, int((d > 0).sum()), len(d)


def mean_over_runs(records: list[dict], runs: list[str]) -> list[dict]:
    """Per object, each fitted method's scores averaged over several results folders (other fit seeds):
    ``<method> (<run>)`` for every run in ``runs`` becomes ``<method> (mean of N runs)`` (scores nan where any
    run lacks the object or has a non-finite score), so that pairs compare what each method gives on an object,
    not one draw of it. Records of other variants are left as they are; the averaged ones are added."""
    if len(runs) < 2:
        return records
    by: dict[tuple, dict[str, dict]] = {}
    for r in records:
        for run in runs:
            suffix = f" ({run})"
            if r["variant"].endswith(suffix) and " (" not in r["variant"][:-len(suffix)]:
                by.setdefault((r["variant"][:-len(suffix)], r["photo"], r["id"]), {})[run] = r
    added = []
    for (method, photo, oid), got in by.items():
        first = next(iter(got.values()))
        scores = {k: (float(np.mean([got[run][k] for run in runs]))
                      if len(got) == len(runs) and all(math.isfinite(got[run][k]) for run in runs) else float("nan"))
                  for k in SCORES}
        added.append({**first, **scores, "variant": f"{method} (mean of {len(runs)} runs)"})
    return records + added


def table(records: list[dict]) -> str:
    variants = sorted({r["variant"] for r in records}, key=lambda v: (not v.startswith("truth"), v))
    lines = ["| variant | objects | region PSNR LDR | object PSNR LDR | shadow PSNR LDR |", "|---|:---:|:---:|:---:|:---:|"]
    for v in variants:
        rs = [r for r in records if r["variant"] == v]
        cells = []
        for key in SCORES:
            x = np.array([r[key] for r in rs if math.isfinite(r[key])])
            cells.append(f"{x.mean():.2f} ± {x.std():.2f}" if len(x) else "–")
        lines.append(f"| {v} | {len(rs)} | " + " | ".join(cells) + " |")
    lines += ["", "| paired (a − b) | region | object | shadow |", "|---|:---:|:---:|:---:|"]
    pairs = [("oracle", "oracle-envmap"), ("oracle unenclosed", "oracle-envmap"), ("oracle", "oracle unenclosed"),
             ("oracle true albedo", "oracle-envmap true albedo"), ("oracle true geometry", "oracle-envmap true geometry")]
    pairs += [(v[:-len(" true albedo")], v) for v in variants if v.endswith(" true albedo")]
    pairs += [(v, v[:-len(" true geometry")]) for v in variants if v.endswith(" true geometry")]
    pairs += [(v, v.replace("prior (", "prior-envmap (")) for v in variants
              if v.startswith("prior (") and v.endswith(" true geometry")]
    pairs += [(v, v.replace("prior (", "prior-envmap (")) for v in variants
              if v.startswith("prior (") and not v.endswith(" true geometry")]
    pairs += [(v, v + " unenclosed") for v in variants if v.startswith("prior (") and v + " unenclosed" in variants]
    pairs += [(v, v[:-len(" true level")]) for v in variants if v.endswith(" true level")]
    pairs += [(v, v[:-len(" reference albedo")]) for v in variants if v.endswith(" reference albedo")]
    pairs += [(v, v + " at infinity") for v in variants if v + " at infinity" in variants]
    pairs += [(v, v[:-len(" true depth")]) for v in variants if v.endswith(" true depth")]
    pairs += [(v, v[:-len(" true depth")] + " at infinity") for v in variants
              if v.endswith(" true depth") and v[:-len(" true depth")] + " at infinity" in variants]
    pairs += [(v, v[:-len(" true radiance")]) for v in variants if v.endswith(" true radiance")]
    pairs = [p for p in pairs if all(any(r["variant"] == x for r in records) for x in p)]
    for by_photo in (False, True):
        if by_photo:
            lines += ["", "| paired per photo (a − b, each photo's objects averaged) | region | object | shadow |",
                      "|---|:---:|:---:|:---:|"]
        for a, b in pairs:
            cells = []
            for key in SCORES:
                p = paired(records, a, b, key, by_photo=by_photo)
                cells.append("–" if p is None else f"{p[0]:+.2f} [{p[1]:+.2f}, {p[2]:+.2f}] {p[3]}/{p[4]}")
            lines.append(f"| {a} − {b} | " + " | ".join(cells) + " |")
    # against distance: the lights as the pipeline uses them, not the diagnostic variants
    plain = [p for p in pairs if all(x not in p[0] + p[1] for x in ("unenclosed", "true albedo", "true geometry"))
             and ("true level" in p[0]) == ("true level" in p[1])
             and ("reference albedo" in p[0]) == ("reference albedo" in p[1])
             and ("true depth" in p[0]) == ("true depth" in p[1])]
    lines += ["", distance_table(records, plain)]
    return "\n".join(lines)


def distance_table(records: list[dict], pairs, reps: int = 2000) -> str:
    """The 2.5D light's advantage against distance: per pair, a − b on region, object and shadow PSNR by
    stratum (or by distance tercile when the objects have none), and the slope over distance with 95 %
    bootstrap intervals over objects and over photos (a photo's objects share its fitted light)."""
    lines = ["| pair | score | " + " | ".join(("near", "middle", "far", "raised"))
             + " | slope (dB/m) [over objects] | over photos |",
             "|---|---|" + ":---:|" * 6]
    for a, b in pairs:
        ka = {(r["photo"], r["id"]): r for r in records if r["variant"] == a}
        kb = {(r["photo"], r["id"]): r for r in records if r["variant"] == b}
        keys = [k for k in ka if k in kb]
        if len(keys) < 4:
            continue
        dist = np.array([ka[k]["distance_m"] for k in keys])
        strata = [ka[k].get("stratum") for k in keys]
        if not any(strata):
            t1, t2 = np.percentile(dist, [100 / 3, 200 / 3])
            strata = ["near" if d <= t1 else "middle" if d <= t2 else "far" for d in dist]
        for key in SCORES:
            diff = np.array([ka[k][key] - kb[k][key] for k in keys])
            ok = np.isfinite(diff)
            cells = []
            for s in ("near", "middle", "far", "raised"):
                sel = ok & np.array([x == s for x in strata])
                if sel.sum() >= 2:
                    d = diff[sel]
                    lo, hi = bootstrap_mean_interval(d, resamples=reps, seed=0)
                    cells.append(f"{d.mean():+.2f} [{lo:+.2f}, {hi:+.2f}] n={len(d)}")
                else:
                    cells.append("–")
            slope, lo, hi = bootstrap_slope_interval(dist[ok], diff[ok], resamples=reps)
            photos = [k[0] for k, good in zip(keys, ok) if good]
            _, plo, phi = bootstrap_slope_interval(dist[ok], diff[ok], resamples=reps, clusters=photos)
            # objects all at one distance have no slope to fit
            cells.append("–" if not math.isfinite(slope) else f"{slope:+.2f} [{lo:+.2f}, {hi:+.2f}]")
            cells.append("–" if not math.isfinite(plo) else f"[{plo:+.2f}, {phi:+.2f}]")
            lines.append(f"| {a} − {b} | {key} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("bench", type=Path)
    ap.add_argument("--results", type=Path, action="append", default=[], help="a results folder with fitted lights")
    ap.add_argument("--photos", type=int, default=0, help="only the first N photos (0: all)")
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--hi-spp", type=int, default=256)
    ap.add_argument("--out", type=Path, default=Path("results/insertion-diagnosis.json"))
    ap.add_argument("--quick", action="store_true", help="each light once: no unenclosed, other-seed or more-samples variant")
    ap.add_argument("--albedo", action="store_true", help="also composite with the local scene's true albedo")
    ap.add_argument("--geometry", action="store_true", help="also composite with the local scene's true shape")
    ap.add_argument("--level", action="store_true",
                    help="also composite each fitted light at the true level and colour of its diffuse probes")
    ap.add_argument("--reference", action="store_true",
                    help="also composite each fitted light at the level where one photo object has its true albedo")
    ap.add_argument("--true-depth", action="store_true",
                    help="also composite the fitted prior's radiance on the room's true shape, and at infinity")
    ap.add_argument("--truth-spp", type=int, default=0,
                    help="score against the truth rendered again at this many samples (procedural rooms only; "
                         "truth noise then at --spp)")
    args = ap.parse_args(argv)
    photos = sorted(p for p in args.bench.glob("photo-*") if p.is_dir())
    photos = photos[:args.photos] if args.photos else photos
    done = json.loads(args.out.read_text()) if args.out.is_file() else {}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    for k, d in enumerate(photos):
        if d.name in done:
            continue
        print(f"[{k + 1}/{len(photos)}] {d.name}", file=sys.stderr, flush=True)
        done[d.name] = diagnose_photo(d, args.results, args.spp, args.hi_spp, args.quick, args.albedo,
                                     args.geometry, args.truth_spp, args.level,
                                     args.reference, args.true_depth)
        tmp = args.out.with_suffix(".tmp")
        tmp.write_text(json.dumps(done))
        tmp.replace(args.out)
    records = [r for d in photos if d.name in done for r in done[d.name]]
    print(table(mean_over_runs(records, [res.name for res in args.results])))


if __name__ == "__main__":
    main()
