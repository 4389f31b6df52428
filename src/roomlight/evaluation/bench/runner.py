"""``roomlight bench run``: fit every benchmark scene with every method and score the result.

For each case (scene x method), in manifest order:

1. ``fit_scene(scene, method, config, out_dir=CASE/fit, model=...)`` fits the input view;
2. the input and evaluation views are re-rendered under the recovered emitter at ``eval_spp``
   (seeds differ from the ground truth's, so the two renders have independent noise);
3. both are scored against the ground-truth HDR renders over the views' masks
   (:mod:`roomlight.evaluation.harness.metrics`).

Layout of ``RES``::

    RES/run.json                                   settings (checked on resume)
    RES/cases/<panorama>/<material>/<method>/
        result.json      metrics, timings, emitter kind, and per view the share of its objects'
                         surface outside the recovered emitter (written last: marks the case done)
        recovered.exr    recovered radiance (+ Z depth when it has one)
        input.exr, eval.exr                        renders under the recovered emitter
        fit/             the fit's own outputs (history, emitter bundle, loss curve, ...)
        error.json       instead of result.json when the case failed (retried on the next run)

The pseudo-method ``oracle`` (not a fit) returns the ground-truth emitter itself: its scores are
the Monte-Carlo noise floor of the metrics at ``eval_spp`` against the ground truth's ``spp``.

Running, resuming (a case with a ``result.json`` is skipped), sharding, failures and ``--scheduler``
are the harness's (:mod:`roomlight.evaluation.harness.runner`), the same for every benchmark kind.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass
from functools import partial
from pathlib import Path

import torch

from roomlight.core.render.variant import thread_record
from roomlight.evaluation.bench.builder import read_manifest
from roomlight.evaluation.harness.errors import BenchError
from roomlight.evaluation.harness.records import RESULT, RUN_FILE, check_run_file, json_default, record_failure, write_json
from roomlight.evaluation.bench.rendering import render_view
from roomlight.evaluation.harness.metrics import score_view
from roomlight.evaluation.harness.runner import Case, RunSummary, parse_shard, run_cases, shard_cases
from roomlight.fitting.methods import check_methods

__all__ = ["SceneCase", "EVAL_SEEDS", "list_cases", "run_case", "run_benchmark", "known_methods", "oracle_fit",
           "ORACLE", "DEFAULT_EVAL_SPP",
           # the harness's, re-exported for the commands and scripts that import them from here
           "RunSummary", "parse_shard", "check_run_file", "record_failure", "write_json", "RESULT", "RUN_FILE"]

#: Samples per pixel of the scoring re-renders (the paper uses 4096).
DEFAULT_EVAL_SPP = 256

#: Pseudo-method: the ground-truth emitter, re-rendered (the metrics' noise floor).
ORACLE = "oracle"
#: Seeds of the re-renders under recovered emitters (the ground truth used 0 and 1 << 20).
EVAL_SEEDS = {"input": 7_000_001, "eval": 7_000_001 + (1 << 20)}
VIEWS = ("input", "eval")


@dataclass(frozen=True)
class SceneCase(Case):
    """One (scene, method) pair: ``item`` is ``<panorama>/<material>``, ``source`` its scene.json."""

    panorama: str = ""
    material: str = ""


def list_cases(bench_dir, methods, shard=(0, 1)) -> list[SceneCase]:
    """Every (scene, method) case of the benchmark, in manifest x method order, then sharded."""
    bench = Path(bench_dir)
    manifest = read_manifest(bench)
    cases = [SceneCase(s["id"], m, bench / s["scene"], s["panorama"], s["material"])
             for s in manifest["scenes"] for m in methods]
    return shard_cases(cases, shard)


def emitter_depth(result) -> torch.Tensor | None:
    """(H, W) float32 depth of a recovered emitter at its radiance's resolution: its own map, a
    constant for a sphere proxy, None for an environment map (light at infinity)."""
    from roomlight.core.emitter.sphere import sphere_depth
    from roomlight.core.light import parse_emitter_kind

    if result.depth is not None:
        return result.depth.detach().float().cpu()
    kind = parse_emitter_kind(result.emitter_kind)
    if kind.name == "sphere":
        return sphere_depth(result.radiance.shape[0], result.radiance.shape[1], kind.radius)
    return None


def _write_recovered(path: Path, result, depth: torch.Tensor | None) -> None:
    """``recovered.exr``: the radiance, and ``depth`` (:func:`emitter_depth`) as Z when there is one."""
    from roomlight.core.io import write_panorama

    rad = result.radiance.detach().float().cpu()
    write_panorama(path, (rad.numpy(), None if depth is None else depth.numpy()),
                   half=False, metadata={"emitter_kind": str(result.emitter_kind)})


def objects_outside(scene, depth: torch.Tensor | None, per_object: int = 256) -> dict[str, float] | None:
    """Per view, the share of its objects' surface points that an emitter of this ``depth``
    (:func:`emitter_depth`) does not enclose (negative clearance,
    :func:`roomlight.fitting.inverse.repulsion.clearance`); None for an environment map (no depth).

    An object outside a 2.5D light is hidden behind it from the capture point and sees only its
    back faces, which emit nothing, so a case whose evaluation share is above 0 explains a bad
    score by where the light ended up rather than by what it looks like.
    """
    from roomlight.fitting.inverse.repulsion import clearance
    from roomlight.fitting.scene.build import scene_points

    if depth is None:
        return None
    depth = depth.double()
    shares = {}
    for view in VIEWS:
        points = scene_points(scene, scene.view(view).objects, per_object, seed=0).double()
        shares[view] = float((clearance(depth, points) < 0).double().mean())
    return shares


def _write_render(path: Path, img: torch.Tensor) -> None:
    from roomlight.core.io import write_exr

    a = img.detach().float().cpu().numpy()
    write_exr(path, {"R": a[..., 0], "G": a[..., 1], "B": a[..., 2]}, half=False)


def run_case(case: SceneCase, out_dir, fit, fit_config=None, model=None, eval_spp: int = 256,
             max_depth: int = 4, progress: bool = True) -> dict:
    """Fit, re-render and score one case; writes its directory and returns the result record.

    Args:
        fit: the fitting function, ``fit(scene, method, config, out_dir=..., model=..., progress=...)``
            returning an object with ``radiance`` (H, W, 3), ``depth`` (H, W) or None,
            ``emitter_kind``, and optionally ``history``, ``best_iteration``, ``seconds``.
    """
    from roomlight.fitting.scene.build import load_view_target
    from roomlight.fitting.scene.build import load_scene

    cdir = case.directory(out_dir)
    cdir.mkdir(parents=True, exist_ok=True)
    scene = load_scene(case.source)
    t0 = time.perf_counter()
    if case.method == ORACLE:
        result = oracle_fit(scene)
    else:
        result = fit(scene, case.method, fit_config, out_dir=cdir / "fit", model=model, progress=progress)
    fit_seconds = time.perf_counter() - t0
    depth = emitter_depth(result)
    _write_recovered(cdir / "recovered.exr", result, depth)
    t1 = time.perf_counter()
    metrics = {}
    for view in VIEWS:
        v = scene.view(view)
        gt, mask = load_view_target(v, prefer="hdr")
        img = render_view(scene, v, result.radiance, result.depth, str(result.emitter_kind), eval_spp,
                          EVAL_SEEDS[view], max_depth)
        _write_render(cdir / f"{view}.exr", img)
        metrics[view] = score_view(img, gt, mask)
    history = list(getattr(result, "history", []) or [])
    record = {
        "scene": case.item, "scene_path": str(Path(case.source).resolve()), "panorama": case.panorama,
        "material": case.material, "method": case.method,
        "emitter_kind": str(result.emitter_kind), "metrics": metrics,
        "fit_seconds": float(getattr(result, "seconds", 0.0) or fit_seconds),
        "wall_seconds": fit_seconds, "eval_seconds": time.perf_counter() - t1,
        "best_iteration": getattr(result, "best_iteration", None),
        "iterations": sum(1 for h in history if "total" in h) if history else None,
        "nonfinite_steps": getattr(result, "nonfinite_steps", None),
        "recovered_resolution": list(result.radiance.shape[:2]), "eval_spp": eval_spp, "threads": thread_record(),
        "outside": objects_outside(scene, depth),
        "files": {"recovered": "recovered.exr", "input": "input.exr", "eval": "eval.exr", "fit": "fit"},
    }
    err = cdir / "error.json"
    if err.exists():
        err.unlink()
    write_json(cdir / RESULT, record)
    return record


def oracle_fit(scene):
    """The scene's ground-truth emitter as a :class:`~roomlight.fitting.inverse.fitter.FitResult` of method
    ``oracle``: its light is the true panorama (radiance (H, 2H, 3), depth (H, 2H) metres) as a 2.5D
    area light; nothing was fitted, so it has no history, best iteration or step counts."""
    from roomlight.fitting.inverse.fitter import FitResult
    from roomlight.core.light import Light

    if scene.emitter is None:
        raise BenchError(f"{scene.root}: the scene has no emitter; the oracle needs the ground truth")
    pano = scene.emitter.load()
    if pano.depth is None:
        raise BenchError(f"{scene.emitter.panorama}: the ground-truth emitter has no depth")
    return FitResult(ORACLE, Light(pano.radiance, pano.depth, "mesh"), best_iteration=None, nonfinite_steps=None)


def _default_fit():
    try:
        from roomlight.fitting.inverse import fit_scene
    except ImportError as exc:  # pragma: no cover - the package ships it
        raise BenchError(f"bench run: the fitting methods (roomlight.fitting.inverse) cannot be imported: {exc}") from None
    return fit_scene


def known_methods() -> tuple[str, ...]:
    """The fitting methods ``bench run`` accepts (``roomlight.fitting.inverse.METHODS``)."""
    from roomlight.fitting.inverse import METHODS

    return tuple(METHODS)


def default_methods() -> tuple[str, ...]:
    """The methods ``bench run`` fits without ``--methods``: every one but the VENI rows, which are
    asked for by name (``--methods ...,veni,veni-d``) since they load models of their own."""
    from roomlight.fitting.methods import FIT, default_run

    return default_run(FIT)


def run_benchmark(bench_dir, out_dir, methods=None, fit_config=None, model=None, eval_spp: int = DEFAULT_EVAL_SPP,
                  shard=(0, 1), max_depth: int = 4, progress: bool = True, fit=None, scheduler=None,
                  model_name: str | None = None) -> RunSummary:
    """Run (a shard of) the benchmark; see the module docstring.

    Args:
        bench_dir: a directory written by ``roomlight bench make``.
        out_dir: results folder ``RES``.
        methods: method names (default: every method of ``roomlight.fitting.inverse.METHODS``).
        fit_config: a ``roomlight.fitting.inverse.FitConfig`` (default: the fitter's own defaults).
        model: the prior (a ``PanoVAE``) for the ``prior*`` methods.
        eval_spp: samples per pixel of the re-renders (paper: 4096).
        shard: (i, n), see :func:`parse_shard`.
        fit: the fitting function (default ``roomlight.fitting.inverse.fit_scene``).
        scheduler: a Dask scheduler address (or cluster): run the cases on its workers
            (:func:`roomlight.core.cluster.map_unordered`); the files are the same as in a serial run.
        model_name: where the prior came from, recorded in ``run.json`` for the report.
    """
    if fit is None:
        fit = _default_fit()
        check_methods(methods or (), known_methods() + (ORACLE,))
    methods = tuple(methods) if methods else default_methods()
    bench = Path(bench_dir).resolve()
    out = Path(out_dir)
    list_cases(bench, methods, shard)  # a broken benchmark is refused before anything is written
    out.mkdir(parents=True, exist_ok=True)
    cfg_dict = fit_config.to_dict() if hasattr(fit_config, "to_dict") else (
        dict(vars(fit_config)) if fit_config is not None else None)
    settings = {"bench": str(bench), "methods": list(methods),
                "fit_config": json.loads(json.dumps(cfg_dict, default=json_default)),
                "eval_spp": eval_spp, "max_depth": max_depth}
    if model_name is not None:
        settings["model"] = str(model_name)
    check_run_file(out, settings, ("fit_config", "eval_spp", "max_depth"))
    cases = list_cases(bench, methods, shard)
    # on a cluster the fits print no bars of their own (this process shows the cases)
    one = partial(run_case, out_dir=out, fit=fit, fit_config=fit_config, model=model, eval_spp=eval_spp,
                  max_depth=max_depth, progress=progress and scheduler is None)
    return run_cases(cases, out, one, desc="bench run", progress=progress, scheduler=scheduler)
