"""``roomlight bench run-photos``: fit every photo with every method and score the recovered light.

For each case (photo x method), in manifest order:

1. the method fits the photo case (:func:`roomlight.evaluation.photobench.adapter.fit_photo_case`, the
   fit-photo pipeline; its files go to ``CASE/fit``); the pseudo-methods ``oracle`` and
   ``oracle-envmap`` fit nothing and take the photo's oracle light as a 2.5D light or an env map;
   ``prior-ceiling`` takes the prior's latent fitted to that oracle panorama (the prior's ceiling);
   ``prior-view``, ``prior-samples`` and ``prior-zero`` are ``prior`` from a fixed start (``--init``);
   ``naive-paste`` is a uniform light of the photo's mean colour; ``estimate``, ``estimate-refine`` and
   ``estimate-depth-optional`` are ``roomlight estimate`` (plain, ``--refine``, ``--depth-optional-encoder``)
   on the photo alone: no depth, no mask, the
   camera's field of view and tilt from the case; they fit no materials and insert nothing;
2. the probes are rendered at their true positions under the recovered light and scored against
   the ground truth (:mod:`roomlight.evaluation.photobench.scoring`), and the recovered materials against
   the true ones;
3. when the photo has inserted objects with their truth, they are composited into the photo under the
   recovered light by ``roomlight insert``'s differential rendering (the naive paste: lit alone, no
   shadow) and scored in their regions (:mod:`roomlight.evaluation.photobench.insertion`) against the
   photo's insertion truth; the record says which (``insertion_truth``). A finished case whose photo has
   got another insertion truth since (``make-photos --insert-spp``) is scored again from its saved
   composite when the run resumes, nothing fitted or rendered again (:func:`rescore_insertions`).

Layout of ``RES``::

    RES/run.json                        settings (checked on resume)
    RES/cases/<photo>/<method>/
        result.json       scores per probe material and probe, material errors, timings (written last)
        recovered.exr     the recovered radiance (+ Z depth when it has one)
        probes_<m>.exr    the probes under the recovered light, one per probe material
        insert.exr        the inserted objects composited under it (photos built with them)
        fit/              the fit's own files (panorama.exr, emitter/, materials.json, result.json, ...)
        error.json        instead of result.json when the case failed (retried on the next run)

Running, resuming (a case with a ``result.json`` is skipped, its insertion scores brought up to date), sharding, failures and ``--scheduler``
are the harness's (:mod:`roomlight.evaluation.harness.runner`), as for ``bench run``.
"""

from __future__ import annotations

import time
from functools import partial
from pathlib import Path

from roomlight.core.render.variant import thread_record
from roomlight.errors import RoomlightError
from roomlight.evaluation.harness.records import RESULT, RUN_FILE, check_run_file, write_json
from roomlight.evaluation.harness.runner import Case, RunSummary, run_cases, shard_cases
from roomlight.core.light import Light
from roomlight.fitting.methods import ESTIMATE_ROWS, PHOTO, check_methods, default_run, methods_for
from roomlight.fitting.methods import method as method_record
from roomlight.evaluation.photobench.adapter import PHOTO_FIT_METHODS, fit_photo_case
from roomlight.evaluation.photobench.ceiling import CEILING, prior_ceiling_light
from roomlight.evaluation.photobench import case as fmt
from roomlight.evaluation.photobench.insertion import NAIVE, insert_truth_stamp
from roomlight.evaluation.photobench.builder import read_photo_manifest
from roomlight.evaluation.photobench.scoring import (SCORE_MAX_DEPTH, load_truth, material_errors, oracle_light,
                                          probes_outside,
                                          score_light)

__all__ = ["ORACLES", "REFERENCES", "KNOWN_METHODS", "DEFAULT_METHODS", "DEFAULT_EVAL_SPP", "RESULT", "RUN_FILE",
           "list_photo_cases", "run_photo_case", "run_photo_benchmark"]

#: Pseudo-methods: the photo's true light as a 2.5D light, or shown at infinity (by its light's kind).
ORACLES = {m: method_record(m).light for m in methods_for(PHOTO, fitted=False) if method_record(m).source == "truth"}
#: References that fit nothing from the photograph: the oracles, the prior's ceiling
#: (:mod:`roomlight.evaluation.photobench.ceiling`) and the naive paste. Their lights live in the oracle's frame.
REFERENCES = methods_for(PHOTO, fitted=False)
#: ``roomlight estimate`` on the photo alone (plain, refined, read by a depth-optional encoder).
ESTIMATES = tuple(m for m in methods_for(PHOTO) if m in ESTIMATE_ROWS)
KNOWN_METHODS = PHOTO_FIT_METHODS + ESTIMATES + REFERENCES
#: Without ``--methods``: the paper's method and the env-map baselines (VENI rows: by name).
DEFAULT_METHODS = default_run(PHOTO)
#: Samples per pixel of the scoring renders.
DEFAULT_EVAL_SPP = 256


def list_photo_cases(bench_dir, methods, shard=(0, 1)) -> list[Case]:
    """Every (photo, method) case (``item``: the photo id; ``source``: its case folder), in manifest x
    method order, then sharded."""
    bench = Path(bench_dir)
    manifest = read_photo_manifest(bench)
    return shard_cases([Case(p["id"], m, bench / p["case"]) for p in manifest["photos"] for m in methods], shard)


def _recovered(fit: dict) -> Light:
    for key in ("radiance", "emitter_kind", "light_from_camera"):
        if key not in fit:
            raise RoomlightError(f"the fit returned no {key!r}")
    return Light(fit["radiance"], fit.get("depth"), str(fit["emitter_kind"]), fit["light_from_camera"])


def run_photo_case(case: Case, out_dir, preset: str = "paper", model=None, eval_spp: int = DEFAULT_EVAL_SPP,
                   fit=None, progress: bool = False, overrides: dict | None = None) -> dict:
    """Fit (or take the oracle), score and write one case; returns its ``result.json`` record.

    ``fit``: the fitting function, :func:`~roomlight.evaluation.photobench.adapter.fit_photo_case` by default;
    ``overrides``: fit-photo settings replacing the preset's.
    """
    from roomlight.core.io import write_panorama
    from roomlight.evaluation.photobench.case import write_rgb_exr

    fit = fit or fit_photo_case
    cdir = case.directory(out_dir)
    cdir.mkdir(parents=True, exist_ok=True)
    truth = load_truth(case.source)
    t0 = time.perf_counter()
    materials = fitted_materials = None
    if case.method in ORACLES:
        light = oracle_light(case.source, ORACLES[case.method], truth)
        fit_seconds = 0.0
    elif case.method == CEILING:
        light = prior_ceiling_light(case.source, model, truth)
        fit_seconds = time.perf_counter() - t0
    elif case.method == NAIVE:
        from roomlight.evaluation.photobench.insertion import naive_light

        light = naive_light(case.source)
        fit_seconds = 0.0
    elif case.method in ESTIMATES:
        light = _estimate_light(case.source, model, case.method)
        fit_seconds = time.perf_counter() - t0
    else:
        out = fit(case.source, case.method, preset, cdir / "fit", model=model, progress=progress,
                  overrides=overrides)
        fitted_materials = out.get("materials") or {}
        light = _recovered(out)
        materials = material_errors(truth.materials, out.get("materials") or {})
        fit_seconds = float(out.get("seconds", time.perf_counter() - t0))
    wall = time.perf_counter() - t0
    write_panorama(cdir / "recovered.exr", light.to_numpy(), half=False,
                   metadata={"emitter_kind": light.kind, "light_from_camera": light.frame.tolist()})
    t1 = time.perf_counter()
    renders: dict = {}
    # fitted through fit-photo, with the photo's given depth: the probes stand where that depth puts them
    fitted = case.method in PHOTO_FIT_METHODS
    scores = score_light(truth, light, eval_spp, renders=renders, given_depth=fitted)
    for m, img in renders.items():
        write_rgb_exr(cdir / f"probes_{m}.exr", img)
    outside = probes_outside(truth, light, given_depth=fitted)
    insertion = None if case.method in ESTIMATES else _insertion(case, light, truth, fitted_materials, preset,
                                                                   overrides, eval_spp, cdir)
    record = {"photo": case.item, "case_dir": str(Path(case.source).resolve()), "method": case.method,
              "emitter_kind": light.kind, "probes": scores, "materials": materials,
              "probes_outside": outside, "insertion": insertion,
              "insertion_truth": insert_truth_stamp(Path(case.source) / fmt.TRUTH) if insertion else None,
              "depth_factors": truth.depth_factors, "fit_seconds": fit_seconds, "wall_seconds": wall,
              "eval_seconds": time.perf_counter() - t1, "eval_spp": eval_spp, "max_depth": SCORE_MAX_DEPTH,
              "recovered_resolution": list(light.radiance.shape[:2]), "threads": thread_record(),
              "files": {"recovered": "recovered.exr", **{m: f"probes_{m}.exr" for m in renders},
                        **({"insert": INSERT_COMPOSITE} if insertion else {}),
                        **({"fit": "fit"} if fitted else {})}}
    (cdir / "error.json").unlink(missing_ok=True)
    write_json(cdir / RESULT, record)
    return record


def _estimate_light(case_dir, model, row: str) -> Light:
    """``roomlight estimate``'s light for a photo case: its linear image clipped at 1 as a recording is, its
    camera and tilt; its depth and mask left unused (the light's frame: camera -> room, no shift)."""
    import numpy as np

    from roomlight.fitting.photo.case import load_photo
    from roomlight.fitting.photo.estimate import estimate_light, estimate_row_settings

    photo = load_photo(str(case_dir))
    est = estimate_light(np.minimum(photo.image, 1.0), photo.intrinsics, model, photo.pitch_deg, photo.roll_deg,
                         **estimate_row_settings(row))
    return est.light


def _insertion(case: Case, light, truth, fitted_materials, preset, overrides, spp: int, cdir: Path):
    """Per inserted object, the composite's scores (None for a photo built without inserted objects)."""
    from roomlight.evaluation.photobench import case as fmt
    from roomlight.evaluation.photobench.insertion import composite_for_light, insertion_scores, read_insert_truth

    ins = read_insert_truth(Path(case.source) / fmt.TRUTH)
    if ins is None:
        return None
    image, labels, objects = ins
    # a reference fits no materials: the local scene's objects get their true ones
    materials = fitted_materials if fitted_materials else {k: m.to_dict() for k, m in truth.materials.items()}
    composite = composite_for_light(case.source, light, materials, objects, truth.camera, preset, overrides, spp,
                                    local_scene=case.method != NAIVE)
    fmt.write_rgb_exr(cdir / INSERT_COMPOSITE, composite)
    return insertion_scores(composite, image, labels, objects, truth.camera.matrix)


#: A case's composite of the photo's inserted objects under its light.
INSERT_COMPOSITE = "insert.exr"
#: The insertion truth of a record made before records said which (the render with the photo's samples).
_PHOTO_SAMPLES_TRUTH = {"image": "insert.exr", "spp": None}


def rescore_insertions(cases, out_dir) -> tuple[list[str], dict[str, str]]:
    """Score again the inserted objects of every finished case (``result.json``) that scored them against
    another truth than its photo's today, from the composite it saved; nothing is fitted or rendered again.
    The record keeps its former scores under ``insertion_superseded``. Returns (the names scored again,
    name -> why a case could not be: its composite is gone)."""
    import json

    from roomlight.evaluation.photobench import case as fmt
    from roomlight.evaluation.photobench.insertion import insert_truth_stamp, insertion_scores, read_insert_truth

    out = Path(out_dir)
    done, failed = [], {}
    for case in cases:
        path = case.directory(out) / RESULT
        if not path.is_file():
            continue
        record = json.loads(path.read_text())
        stamp = insert_truth_stamp(Path(case.source) / fmt.TRUTH)
        if record.get("insertion") is None or stamp is None:
            continue
        before = record.get("insertion_truth", _PHOTO_SAMPLES_TRUTH)
        if before == stamp:
            continue
        composite_file = path.parent / INSERT_COMPOSITE
        if not composite_file.is_file():
            failed[case.name] = (f"its inserted objects were scored against another truth ({before['image']}) and "
                                 f"its composite ({INSERT_COMPOSITE}) is gone: delete {path} to run it again")
            continue
        image, labels, objects = read_insert_truth(Path(case.source) / fmt.TRUTH)
        camera = load_truth(case.source).camera
        scores = insertion_scores(fmt.read_rgb_exr(composite_file), image, labels, objects, camera.matrix)
        record["insertion_superseded"] = {"insertion_truth": before, "insertion": record["insertion"]}
        record.update(insertion=scores, insertion_truth=stamp)
        write_json(path, record)
        done.append(case.name)
    return done, failed


def run_photo_benchmark(bench_dir, out_dir, methods=None, preset: str = "paper", model=None,
                        eval_spp: int = DEFAULT_EVAL_SPP, shard=(0, 1), progress: bool = True, fit=None,
                        model_name: str | None = None, overrides: dict | None = None, scheduler=None,
                        view_encoder_name: str | None = None) -> RunSummary:
    """Run (a shard of) the photo benchmark; see the module docstring.

    Args:
        bench_dir: a folder written by ``roomlight bench make-photos``; out_dir: the results folder.
        methods: method names (default :data:`DEFAULT_METHODS`); see :data:`KNOWN_METHODS`.
        preset: the fit-photo preset; overrides: settings replacing the preset's (``--set``);
            model: the prior for the prior methods.
        fit: the fitting function (default: :func:`~roomlight.evaluation.photobench.adapter.fit_photo_case`).
        model_name: where the prior came from, recorded in ``run.json``.
        view_encoder_name: where the prior's view encoder came from when it is not the one beside the
            prior (``--view-encoder``); recorded, and a results folder made with another is refused.
        scheduler: a Dask scheduler address (or cluster): run the cases on its workers, as ``bench run``.
    """
    methods = check_methods(methods, KNOWN_METHODS) if methods else DEFAULT_METHODS
    if eval_spp < 1:
        raise RoomlightError(f"--eval-spp must be at least 1, got {eval_spp}")
    bench = Path(bench_dir).resolve()
    cases = list_photo_cases(bench, methods, shard)  # a broken benchmark is refused before anything is written
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    settings = {"bench": str(bench), "kind": "photos", "methods": list(methods), "preset": preset,
                "overrides": dict(overrides or {}), "eval_spp": eval_spp, "max_depth": SCORE_MAX_DEPTH}
    if model_name is not None:
        settings["model"] = str(model_name)
    settings["view_encoder"] = None if view_encoder_name is None else str(view_encoder_name)
    check_run_file(out, settings, ("preset", "overrides", "eval_spp", "max_depth", "view_encoder"))
    rescored, stale = rescore_insertions(cases, out)
    one = partial(run_photo_case, out_dir=out, preset=preset, model=model, eval_spp=eval_spp, fit=fit,
                  progress=False, overrides=overrides)
    summary = run_cases(cases, out, one, desc="run-photos", progress=progress, scheduler=scheduler)
    summary.rescored.extend(rescored)
    summary.failed.update(stale)
    return summary
