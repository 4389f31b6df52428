"""``roomlight bench make-photos``: rendered photographs of procedural rooms with true light transport.

Photo ``i`` (``OUT/photo-0000i/``, the case format of :mod:`roomlight.evaluation.photobench.case`):

1. a room from the synthetic generator (``generate_room(room_seed)``; the seed is drawn from
   ``(seed, i)``, and the next one is drawn when the room cannot be staged);
2. the staging of :mod:`roomlight.evaluation.photobench.staging`: an eye-height camera looking at a
   furnished part of the room, 2-3 inserted objects with principled materials, probe positions;
3. the **photo**: the room with the objects, path-traced (Mitsuba ``path``, ``max_depth``,
   ``spp``) through :mod:`roomlight.evaluation.photobench.tracing`, exposed so that the frame's
   log-average luminance is ``key`` (k = key / log-average; k is baked into every radiance
   written: photo, probe renders, oracle light);
4. exact z-depth at pixel centres (ray casting the photo's scene), and ``mask.png``: label k
   where a pixel is wholly covered by object k (``supersample``^2 rays), 0 elsewhere;
5. the **truth**: the same scene with all probes added, one render per probe material (diffuse,
   matte, mirror), same camera, of the window around the probes (their pixels' bounding box
   grown by 2 px) at ``probe_spp``: the mean of two independent halves, whose difference
   (``noise_floor``: the metrics between the halves) tells how noisy the truth is; the probes'
   mask (the whole frame); the new objects inserted for the insertion scores, rendered with the photo's
   samples and seed and once more at ``insert_spp`` with a seed of their own (the clean truth they are
   scored against; :mod:`roomlight.evaluation.photobench.insertion`); and the **oracle
   light**: the room without objects or probes captured as a radiance + radial depth panorama at
   the oracle centre (the representation's ceiling: what a perfect method could recover);
6. ``depth.exr`` for the methods: the exact depth, or a degraded copy (``depth_noise``,
   ``depth_scale``; :mod:`roomlight.evaluation.photobench.degrade`).

A photo is built in a hidden temporary folder and renamed into place when complete; its
``truth/photo.json`` records the settings. A rerun skips finished photos; one finished with
other depth settings only gets its ``depth.exr`` rewritten, one with another ``insert_spp`` only its
clean insertion truth. ``shard=(i, n)`` builds photos
i, i + n, ...; ``OUT/manifest.json`` lists every finished photo of ``0 .. n-1`` (run once more
without a shard after sharded builds to complete it).
"""

from __future__ import annotations

import json
import os
import shutil
import time
from pathlib import Path

import numpy as np

from roomlight.evaluation.bench.builder import read_record
from roomlight.errors import RoomlightError
from roomlight.evaluation.photobench import case as fmt
from roomlight.evaluation.photobench.config import PhotoBenchConfig
from roomlight.evaluation.photobench.degrade import degrade_depth
from roomlight.evaluation.photobench.objects import PROBE_MATERIALS
from roomlight.evaluation.photobench.staging import StagingError, palette, stage_photo

__all__ = ["MANIFEST", "MANIFEST_VERSION", "ROOMS_PER_PHOTO", "photo_name", "build_photo", "update_depth",
           "update_insert_truth",
           "render_probe_truth", "probe_window",
           "make_photo_benchmark", "read_photo_manifest", "photo_seeds", "room_of_record", "PhotoBuildError"]

MANIFEST = "manifest.json"
MANIFEST_VERSION = 1
#: Rooms tried for one photo before it is reported as failed.
ROOMS_PER_PHOTO = 8
_SALT_ROOM, _SALT_STAGE, _SALT_RENDER, _SALT_DEPTH = 0x726F6F6D, 0x73746167, 0x72656E64, 0x64657074
_SALT_INSERT = 0x696E7374


class PhotoBuildError(RoomlightError):
    """The photo benchmark cannot be built (bad folder, no room could be staged)."""


def photo_name(index: int) -> str:
    return f"photo-{index:05d}"


def photo_seeds(config: PhotoBenchConfig, index: int) -> dict:
    """The render seeds of a photo: the photo, one per probe material, the oracle, the inserted objects'
    clean truth."""
    base = int(np.random.default_rng([config.seed, index, _SALT_RENDER]).integers(0, 2**29))
    seeds = {"photo": base}
    for k, m in enumerate(PROBE_MATERIALS):
        seeds[f"probes_{m}"] = base + 1 + k
    seeds["oracle"] = base + 1 + len(PROBE_MATERIALS)
    seeds["insert"] = base + 2 + len(PROBE_MATERIALS)
    return seeds


def _depth_for_methods(true_depth: np.ndarray, config: PhotoBenchConfig, index: int) -> np.ndarray:
    rng = np.random.default_rng([config.seed, index, _SALT_DEPTH])
    return degrade_depth(true_depth, config.depth_noise, config.depth_scale, rng)


#: Generator seeds drawn when looking for a room of the kind a wide-suite photo asks for.
ROOM_SEARCH = 1000


def _room(config: PhotoBenchConfig, rng: np.random.Generator, plan):
    """A generated room: the next seed's (the original suite), or the next one of the plan's kind,
    edited as the plan says (the wide suite); returns (room, what was edited)."""
    from roomlight.datagen.synth.rooms import generate_room
    from roomlight.evaluation.photobench.variety import edit_room, room_matches

    if plan is None:
        return generate_room(int(rng.integers(0, 2**31 - 1))), {}
    for _ in range(ROOM_SEARCH):
        room = generate_room(int(rng.integers(0, 2**31 - 1)))
        if room_matches(room, plan.room_kind):
            return room, edit_room(room, plan, np.random.default_rng([room.seed, _SALT_ROOM]))
    raise PhotoBuildError(f"no {plan.room_kind!r} room among {ROOM_SEARCH} generated rooms")


def room_of_record(record: dict):
    """The generated room a photo was built in, from its record (``truth/photo.json``): the room of its seed,
    repainted and relit as its plan said (the wide suite), so that it can be rendered again. None for a set
    under a captured panorama."""
    from roomlight.datagen.synth.rooms import generate_room
    from roomlight.evaluation.photobench.variety import Plan, edit_room

    if "captured" in record:
        return None
    room = generate_room(int(record["room_seed"]))
    plan = record.get("plan")
    if plan is not None:
        edits = edit_room(room, Plan(**plan), np.random.default_rng([room.seed, _SALT_ROOM]))
        if json.loads(json.dumps(edits)) != record.get("edits", {}):
            raise PhotoBuildError(f"room {room.seed}: its edits rebuilt ({edits}) are not the record's "
                                  f"({record.get('edits', {})}); the generator changed since the photo was built")
    return room


def _stage(config: PhotoBenchConfig, index: int, captured_lights=None):
    """(scenes, staging, what the photo is: its plan, room edits and captured panorama)."""
    from roomlight.evaluation.photobench.roomscene import RoomScenes

    plan = None
    if config.suite == "wide":
        from roomlight.evaluation.photobench.variety import photo_plan

        plan = photo_plan(config, index)
    rng = np.random.default_rng([config.seed, index, _SALT_ROOM])
    problems = []
    for _ in range(ROOMS_PER_PHOTO):
        about: dict = {} if plan is None else {"plan": plan.to_dict()}
        if plan is not None and plan.light == "captured":
            from roomlight.evaluation.photobench.captured import CapturedSet, find_captured_lights

            lights = find_captured_lights(captured_lights)
            panorama = lights[(index // config.captured_every) % len(lights)]
            scenes = CapturedSet(panorama, int(rng.integers(0, 2**31 - 1)), config.max_depth)
            about["captured"] = {"panorama": panorama.name, **scenes.room.summary()}
        else:
            room, edits = _room(config, rng, plan)
            scenes = RoomScenes(room, config.max_depth)
            if edits:
                about["edits"] = edits
        try:
            staging = stage_photo(scenes, np.random.default_rng([config.seed, index, scenes.room.seed, _SALT_STAGE]),
                                  config, fov=None if plan is None else plan.fov)
            return scenes, staging, about
        except StagingError as exc:
            problems.append(str(exc))
    raise PhotoBuildError(f"{photo_name(index)}: no room of {ROOMS_PER_PHOTO} could be staged ({problems[-1]})")


def _halves(spp: int) -> tuple[int, int]:
    return spp - spp // 2, spp // 2


def render_probe_truth(scene, camera, spp: int, seed: int, window, exposure: float):
    """The truth of one probe material: ``(image, (half A, half B))``, each (h, w, 3) float32 of the
    window, times ``exposure``. The halves take ceil(spp / 2) and floor(spp / 2) samples with
    independent seeds; the image is their sample-weighted mean, and their difference measures
    its noise."""
    from roomlight.evaluation.photobench.tracing import trace_image

    counts = _halves(spp)
    halves = [trace_image(scene, camera, n, seed + (1 << 24) * h, window=window) * exposure
              for h, n in enumerate(counts)]
    image = (counts[0] * halves[0].astype(np.float64) + counts[1] * halves[1].astype(np.float64)) / spp
    return image.astype(np.float32), tuple(x.astype(np.float32) for x in halves)


def probe_window(labels: np.ndarray, pad: int = 2) -> tuple[int, int, int, int]:
    """``(x0, y0, w, h)``: the bounding box of the non-zero ``labels`` grown by ``pad`` pixels (in the frame)."""
    ys, xs = np.nonzero(labels)
    if ys.size == 0:
        raise PhotoBuildError("the probes cover no whole pixel")
    h, w = labels.shape
    x0, y0 = max(0, int(xs.min()) - pad), max(0, int(ys.min()) - pad)
    x1, y1 = min(w, int(xs.max()) + pad + 1), min(h, int(ys.max()) + pad + 1)
    return x0, y0, x1 - x0, y1 - y0


def _labels(coverage: np.ndarray) -> np.ndarray:
    """(K, H, W) coverage -> (H, W) uint8 labels: k + 1 where shape k covers the whole pixel."""
    whole = coverage >= 1.0 - 1e-6
    labels = np.zeros(coverage.shape[1:], np.uint8)
    for k in range(len(coverage)):
        labels[whole[k]] = k + 1
    return labels


def build_photo(index: int, out_dir, config: PhotoBenchConfig, captured_lights=None) -> dict:
    """Build photo ``index`` into ``out_dir/photo-<index>`` (see the module docstring); returns its record."""
    from roomlight.evaluation.harness.metrics import score_view
    from roomlight.evaluation.bench.recording import record_ldr, saturated_fraction
    from roomlight.core.color import log_average_np
    from roomlight.core.io import write_panorama
    from roomlight.evaluation.photobench.tracing import emitter_fraction, trace_coverage, trace_depth, trace_image
    from roomlight.datagen.synth.camera import render_depth, render_radiance
    from roomlight.datagen.synth.spec import GENERATOR_VERSION

    t0 = time.perf_counter()
    out = Path(out_dir)
    name = photo_name(index)
    scenes, st, about = _stage(config, index, captured_lights)
    room, room_scene = scenes.room, scenes.base
    open_set = "captured" in about  # rays may leave the set: they get FAR_DEPTH
    seeds = photo_seeds(config, index)
    cam = st.camera
    meshes = {o.id: o.mitsuba_mesh() for o in st.objects}
    photo_scene = scenes.scene(meshes)
    image = trace_image(photo_scene, cam, config.spp, seeds["photo"])
    if not (image > 0).any():
        raise PhotoBuildError(f"{name}: the photo is black: room {room.seed} has no light the camera sees")
    depth = trace_depth(photo_scene, cam)
    if open_set:
        from roomlight.evaluation.photobench.captured import FAR_DEPTH

        depth = np.where(np.isfinite(depth), np.minimum(depth, FAR_DEPTH), FAR_DEPTH).astype(np.float32)
    if not np.isfinite(depth).all() or (depth <= 0).any():
        raise PhotoBuildError(f"{name}: a camera ray left room {room.seed} (depth not finite); a generator bug")
    labels = _labels(trace_coverage(photo_scene, cam, list(meshes.values()), config.supersample))
    k = config.key / log_average_np(image.astype(np.float64))
    if not np.isfinite(k) or k <= 0:
        raise PhotoBuildError(f"{name}: cannot expose the photo (log-average luminance gives k = {k})")

    shapes = {m: {p.id: p.mitsuba_shape(m) for p in st.probes} for m in PROBE_MATERIALS}
    probe_scenes = {m: scenes.scene({**meshes, **shapes[m]}) for m in PROBE_MATERIALS}
    first = PROBE_MATERIALS[0]
    probe_labels = _labels(trace_coverage(probe_scenes[first], cam, list(shapes[first].values()), config.supersample))
    window = probe_window(probe_labels)
    x0, y0, ww, wh = window
    in_window = probe_labels[y0:y0 + wh, x0:x0 + ww] > 0
    probe_renders, noise_floor = {}, {}
    for m in PROBE_MATERIALS:
        probe_renders[m], halves = render_probe_truth(probe_scenes[m], cam, config.probe_spp, seeds[f"probes_{m}"],
                                                      window, k)
        noise_floor[m] = score_view(halves[0], halves[1], in_window)
    from roomlight.evaluation.photobench.insertion import render_insert_truth, stage_inserts

    insert_rng = np.random.default_rng([config.seed, index, _SALT_INSERT])
    strata = None
    if config.insert_placement == "stratified":
        from roomlight.evaluation.photobench.insertion import stage_stratified_inserts

        occupied = [(np.asarray(p.center)[[0, 2]], float(p.radius)) for p in st.probes]
        inserts, strata = stage_stratified_inserts(scenes, meshes, cam, config.inserts, insert_rng, occupied, config)
    else:
        inserts = stage_inserts(st.probes, config.inserts, insert_rng, config.metal_fraction, config.roughness,
                                palette(config), config.metal_colours)
    if inserts:  # the photo's scene with the new objects, with the photo's seed: elsewhere the photo itself
        insert_image, insert_labels = render_insert_truth(scenes, meshes, inserts, cam, config.spp, seeds["photo"],
                                                          config.supersample, k)
        insert_clean = _clean_insert_truth(scenes, meshes, inserts, cam, config, seeds, k, insert_labels)
    oracle_rad = render_radiance(room_scene, st.oracle_center, height=config.oracle_height, spp=config.oracle_spp,
                                 seed=seeds["oracle"]) * k
    oracle_depth = render_depth(room_scene, st.oracle_center, height=config.oracle_height)
    if open_set:
        oracle_depth = np.where(np.isfinite(oracle_depth), np.minimum(oracle_depth, FAR_DEPTH), FAR_DEPTH)
        oracle_depth = oracle_depth.astype(np.float32)

    tmp = out / f".{name}.{os.getpid()}.partial"
    if tmp.exists():
        shutil.rmtree(tmp)
    (tmp / fmt.TRUTH).mkdir(parents=True)
    try:
        photo = image * k
        fmt.write_rgb_exr(tmp / fmt.IMAGE, photo)
        fmt.write_depth_exr(tmp / fmt.DEPTH, _depth_for_methods(depth, config, index))
        fmt.write_png(tmp / fmt.MASK, labels)
        fmt.write_json(tmp / fmt.CAMERA, fmt.camera_json(cam))
        fmt.write_json(tmp / fmt.TRUE_CAMERA, cam.to_dict())
        fmt.write_depth_exr(tmp / fmt.TRUE_DEPTH, depth)
        fmt.write_png(tmp / fmt.PROBE_MASK, probe_labels)
        fmt.write_png(tmp / fmt.PREVIEW, record_ldr(photo))
        for m, img in probe_renders.items():
            fmt.write_rgb_exr(tmp / fmt.probe_image_name(m), img)
            fmt.write_png(tmp / fmt.probe_image_name(m, "png"), record_ldr(img))
        write_panorama(tmp / fmt.ORACLE, (oracle_rad, oracle_depth), half=False,
                       metadata={"center": [float(c) for c in st.oracle_center], "frame": "world axes",
                                 "exposure": float(k)})
        world_to_cam = np.linalg.inv(cam.matrix)
        materials = {str(o.label): {**o.to_dict()} for o in st.objects}
        fmt.write_json(tmp / fmt.MATERIALS, {"objects": materials,
                                             "bsdf": "Mitsuba principled (base_color, roughness, metallic)"})
        probes = [{**p.to_dict(), "center_camera": [float(c) for c in
                                                    (world_to_cam[:3, :3] @ np.asarray(p.center) + world_to_cam[:3, 3])]}
                  for p in st.probes]
        if inserts:
            from roomlight.evaluation.photobench import insertion as ins

            fmt.write_rgb_exr(tmp / fmt.TRUTH / ins.INSERT_IMAGE, insert_image)
            fmt.write_png(tmp / fmt.TRUTH / ins.INSERT_MASK, insert_labels)
            if insert_clean is not None:
                fmt.write_rgb_exr(tmp / fmt.TRUTH / ins.INSERT_CLEAN, insert_clean)
            fmt.write_json(tmp / fmt.TRUTH / ins.INSERT_JSON, {
                "objects": [o.to_dict() for o in inserts], "image": ins.INSERT_IMAGE, "mask": ins.INSERT_MASK,
                **({"strata": {o.id: s for o, s in zip(inserts, strata)}} if strata is not None else {}),
                "pixels": {str(o.label): int((insert_labels == o.label).sum()) for o in inserts},
                **_clean_entry(config, seeds),
                "note": "the photo's scene with these objects, same camera, seed and samples as the photo"})
        fmt.write_json(tmp / fmt.PROBES, {"probes": probes, "materials": list(PROBE_MATERIALS),
                                          "images": {m: fmt.probe_image_name(m) for m in PROBE_MATERIALS},
                                          "window": list(window), "spp": config.probe_spp, "mask": fmt.PROBE_MASK,
                                          "noise_floor": noise_floor})
        record = {
            "name": name, "index": index, "room_seed": int(room.seed), "generator": GENERATOR_VERSION,
            "room": {"type": room.room_type, "lighting": room.lighting, "shell": room.shell,
                     "height": float(room.height), "capture": [float(c) for c in room.capture]},
            **about, "emitters_in_view": emitter_fraction(photo_scene, cam),
            "camera": cam.to_dict(), "target": [float(c) for c in st.target], "staging_tries": st.tries,
            "objects": [o.to_dict() for o in st.objects], "probes": probes,
            "oracle": {"center": [float(c) for c in st.oracle_center], "height": config.oracle_height,
                       "spp": config.oracle_spp},
            "exposure": float(k), "key": config.key, "seeds": seeds, "probe_window": list(window),
            "noise_floor": noise_floor,
            "pixels": {"objects": {str(o.label): int((labels == o.label).sum()) for o in st.objects},
                       "probes": {str(p.label): int((probe_labels == p.label).sum()) for p in st.probes}},
            "saturated_fraction": saturated_fraction(record_ldr(photo), labels > 0),
            "config": config.scene_settings(), "depth": config.depth_settings(),
            "insert_truth": config.insert_settings(), "seconds": round(time.perf_counter() - t0, 2),
        }
        fmt.write_json(tmp / fmt.RECORD, record)
        final = out / name
        if final.exists():
            shutil.rmtree(final)
        os.replace(tmp, final)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)  # never a half-written photo
        raise
    return record


def update_depth(photo_dir: Path, record: dict, config: PhotoBenchConfig) -> dict:
    """Rewrite a finished photo's ``depth.exr`` for other depth settings (the renders stay)."""
    from roomlight.evaluation.photobench.case import read_depth_exr

    true_depth = read_depth_exr(photo_dir / fmt.TRUE_DEPTH)
    fmt.write_depth_exr(photo_dir / fmt.DEPTH, _depth_for_methods(true_depth, config, int(record["index"])))
    record = {**record, "depth": config.depth_settings()}
    fmt.write_json(photo_dir / fmt.RECORD, record)
    return record


def _clean_insert_truth(scenes, meshes: dict, inserts, camera, config: PhotoBenchConfig, seeds: dict,
                        exposure: float, labels: np.ndarray) -> np.ndarray | None:
    """(H, W, 3) float32: the photo's scene with the new objects at ``insert_spp`` samples per pixel with the
    clean truth's own seed, times ``exposure``; None when ``insert_spp`` is 0. Its objects must cover the
    pixels ``labels`` says (the scene it is rendered in is the photo's)."""
    from roomlight.evaluation.photobench.insertion import render_insert_truth

    if config.insert_spp == 0:
        return None
    image, again = render_insert_truth(scenes, meshes, inserts, camera, config.insert_spp, int(seeds["insert"]),
                                       config.supersample, exposure)
    if not np.array_equal(again, labels):
        raise PhotoBuildError("the inserted objects rendered again cover other pixels than the photo's truth: "
                              "the room or the objects are not the ones the photo was built with")
    return image


def _clean_entry(config: PhotoBenchConfig, seeds: dict) -> dict:
    """``insert.json``'s description of the clean truth (none when ``insert_spp`` is 0)."""
    from roomlight.evaluation.photobench import insertion as ins

    if config.insert_spp == 0:
        return {}
    return {"clean": {"image": ins.INSERT_CLEAN, "spp": config.insert_spp, "seed": int(seeds["insert"]),
                      "note": "the same scene path-traced with a seed of its own: the truth composites are "
                              "scored against"}}


def _insert_settings_of(record: dict) -> dict:
    """The clean insertion truth's settings a photo was built with (none before they existed)."""
    return record.get("insert_truth", {"insert_spp": 0})


def update_insert_truth(photo_dir: Path, record: dict, config: PhotoBenchConfig, captured_lights=None) -> dict:
    """Render a finished photo's clean insertion truth again for ``config.insert_spp`` (or remove it for 0),
    the rest of the photo kept: its room, camera and objects are staged again from their seeds, exactly as
    they were built (checked: the new objects must cover the same pixels)."""
    from roomlight.evaluation.photobench import insertion as ins

    truth_dir = photo_dir / fmt.TRUTH
    index = int(record["index"])
    seeds = {**record["seeds"], "insert": photo_seeds(config, index)["insert"]}
    about = json.loads((truth_dir / ins.INSERT_JSON).read_text()) if (truth_dir / ins.INSERT_JSON).is_file() else None
    if about is not None:
        about.pop("clean", None)
        if config.insert_spp > 0:
            scenes, st, _ = _stage(config, index, captured_lights)
            if [o.id for o in st.objects] != [o["id"] for o in record["objects"]]:
                raise PhotoBuildError(f"{photo_dir.name}: staged again, the photo's objects differ from its record")
            _, labels, inserts = ins.read_insert_truth(truth_dir, clean=False)
            meshes = {o.id: o.mitsuba_mesh() for o in st.objects}
            try:
                image = _clean_insert_truth(scenes, meshes, inserts, st.camera, config, seeds,
                                            float(record["exposure"]), labels.astype(np.uint8))
            except PhotoBuildError as exc:
                raise PhotoBuildError(f"{photo_dir.name}: {exc}") from None
            part = truth_dir / f".{ins.INSERT_CLEAN}.{os.getpid()}.partial.exr"
            fmt.write_rgb_exr(part, image)
            os.replace(part, truth_dir / ins.INSERT_CLEAN)
            about.update(_clean_entry(config, seeds))
        else:
            (truth_dir / ins.INSERT_CLEAN).unlink(missing_ok=True)
        fmt.write_json(truth_dir / ins.INSERT_JSON, about)
    record = {**record, "seeds": seeds, "insert_truth": config.insert_settings()}
    fmt.write_json(photo_dir / fmt.RECORD, record)
    return record


def _finished(photo_dir: Path, config: PhotoBenchConfig) -> dict | None:
    """The record of a finished photo built with the same scene settings, else None."""
    rec = read_record(photo_dir / fmt.RECORD, config.scene_settings())
    if rec is None:
        return None
    needed = [fmt.IMAGE, fmt.DEPTH, fmt.MASK, fmt.CAMERA, fmt.TRUE_CAMERA, fmt.TRUE_DEPTH, fmt.PROBES, fmt.MATERIALS, fmt.PROBE_MASK,
              fmt.ORACLE, *[fmt.probe_image_name(m) for m in PROBE_MATERIALS]]
    return rec if all((photo_dir / n).is_file() for n in needed) else None


def _entry(rec: dict) -> dict:
    return {"id": rec["name"], "case": rec["name"], "index": rec["index"], "room_seed": rec["room_seed"],
            "room_type": rec["room"]["type"], "lighting": rec["room"]["lighting"], "objects": len(rec["objects"]),
            "probes": len(rec["probes"]), "exposure": rec["exposure"], "depth": rec["depth"],
            "seconds": rec.get("seconds")}


def _write_manifest(out: Path, config: PhotoBenchConfig) -> dict:
    photos = []
    for i in range(config.n):
        rec = _finished(out / photo_name(i), config)
        if rec is not None:
            photos.append(_entry(rec))
    manifest = {"version": MANIFEST_VERSION, "kind": "photos", "settings": config.to_dict(), "photos": photos}
    fmt.write_json(out / MANIFEST, manifest)
    return manifest


def make_photo_benchmark(out_dir, config: PhotoBenchConfig | None = None, overwrite: bool = False,
                         shard=(0, 1), progress: bool = True, captured_lights=None) -> dict:
    """Build (a shard of) the photo benchmark; returns the manifest with ``built``, ``updated`` (a new
    depth), ``insert_updated`` (a new clean insertion truth), ``skipped`` and ``failed`` (name -> message)
    of this call added. ``captured_lights``: the folder of
    HDR panoramas for the wide suite's captured-light photos (default: Blender's studio lights,
    :func:`~roomlight.evaluation.photobench.captured.find_captured_lights`)."""
    config = config or PhotoBenchConfig()
    i, n = shard
    if not (n >= 1 and 0 <= i < n):
        raise PhotoBuildError(f"--shard: need 0 <= i < n, got {i}/{n}")
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise PhotoBuildError(f"--out {out}: exists and is not a folder")
    out.mkdir(parents=True, exist_ok=True)
    indices = [k for k in range(config.n) if k % n == i]
    built, updated, insert_updated, skipped, failed = [], [], [], [], {}
    todo, todo_insert = [], []
    for k in indices:
        rec = None if overwrite else _finished(out / photo_name(k), config)
        if rec is None:
            todo.append(k)
            continue
        if rec.get("depth") != config.depth_settings():
            rec = update_depth(out / photo_name(k), rec, config)
            updated.append(photo_name(k))
        if _insert_settings_of(rec) != config.insert_settings():
            todo_insert.append((k, rec))
        elif photo_name(k) not in updated:
            skipped.append(photo_name(k))
    bar = None
    if progress and (todo or todo_insert):
        from roomlight.core.progress import progress_bar

        bar = progress_bar(total=len(indices), initial=len(indices) - len(todo) - len(todo_insert),
                           desc="make-photos", unit="photo")
    jobs = [(k, None) for k in todo] + todo_insert
    try:
        for k, rec in jobs:
            try:
                if rec is None:
                    build_photo(k, out, config, captured_lights)
                    built.append(photo_name(k))
                else:  # the clean insertion truth alone
                    update_insert_truth(out / photo_name(k), rec, config, captured_lights)
                    insert_updated.append(photo_name(k))
            except PhotoBuildError as exc:
                failed[photo_name(k)] = str(exc)
                if bar is not None:
                    bar.write(f"make-photos: {exc}")
            if bar is not None:
                bar.set_postfix_str(photo_name(k))
                bar.update()
    finally:
        if bar is not None:
            bar.close()
    manifest = _write_manifest(out, config)
    return {**manifest, "built": built, "updated": updated, "insert_updated": insert_updated, "skipped": skipped,
            "failed": failed}


def read_photo_manifest(bench_dir) -> dict:
    """``manifest.json`` of a photo benchmark, checked."""
    p = Path(bench_dir)
    f = p / MANIFEST
    if not p.is_dir():
        raise PhotoBuildError(f"{p}: no such folder (build one with `roomlight bench make-photos`)")
    if not f.is_file():
        raise PhotoBuildError(f"{p}: no {MANIFEST}; is this a folder written by `roomlight bench make-photos`?")
    try:
        m = json.loads(f.read_text())
    except ValueError as exc:
        raise PhotoBuildError(f"{f}: not valid JSON ({exc})") from None
    if not isinstance(m, dict) or m.get("kind") != "photos" or not isinstance(m.get("photos"), list):
        raise PhotoBuildError(f"{f}: not a photo benchmark manifest (a synthetic benchmark goes to `bench run`)")
    if not m["photos"]:
        raise PhotoBuildError(f"{f}: lists no finished photo")
    return m
