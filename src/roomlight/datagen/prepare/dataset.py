"""The ``roomlight prepare`` driver: a folder of radiance panoramas -> a training dataset.

Every ``.exr`` / ``.hdr`` panorama under the input folder (any size with W = 2H) goes through

1. reading and validation (:func:`roomlight.core.io.read_panorama`; a file that cannot be read, is not
   2:1, or has NaN / negative radiance is skipped and reported by name, unless a repair was asked for);
2. the blind spot: its extent measured at the input's resolution (``nadir="auto"``) or given in
   degrees, then the panorama resampled to the output resolution and the cap inpainted
   (:func:`roomlight.datagen.prepare.nadir.inpaint_nadir`);
3. depth: the input's own (``depth="keep"``) or estimated from 12 views
   (:func:`roomlight.datagen.prepare.depth.estimate_panorama_depth`);
4. exposure calibration (unit log-average luminance, the factor composed into the metadata);
5. ``OUT/SPLIT/NAME.exr`` (R, G, B half, float32 when a value exceeds the half range, + Z float32
   metres, metadata), as ``roomlight synth`` writes them, and a preview ``OUT/previews/NAME.png``.

``NAME`` is the input's path relative to the input folder without its extension, ``/`` replaced
by ``__``. The split (train / val / test) is decided by a hash of ``NAME``, so it does not change
when files are added. Outputs are written under ``OUT/.partial`` and renamed into place, so an
interrupted run leaves no half-written file, and a rerun skips finished outputs. One JSON line
per input and run is appended to ``OUT/prepare-log.jsonl`` (what was done, or why the input
was skipped); ``OUT/prepare.json`` holds the settings.
"""

from __future__ import annotations

import json
import os
import shutil
import time
import warnings
from concurrent.futures import ProcessPoolExecutor
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from roomlight.errors import InputFileError, RoomlightError

__all__ = ["PrepareConfig", "PrepareJob", "plan_jobs", "prepare_file", "prepare_folder", "output_name",
           "split_for", "LOG_NAME", "SETTINGS_NAME"]

LOG_NAME = "prepare-log.jsonl"
SETTINGS_NAME = "prepare.json"
PARTIAL_DIR = ".partial"
PREVIEW_DIR = "previews"


@dataclass(frozen=True)
class PrepareConfig:
    """Settings of ``roomlight prepare``."""

    nadir: str = "auto"               #: ``auto`` (detect), ``off``, or the cap in degrees from the nadir
    inpainter: str = "telea"          #: telea | ns | lama[:WEIGHTS] | MODULE:FUNCTION
    depth: str = "keep"               #: keep | synthetic[:affine|scale|metric] | moge[:WEIGHTS] | MODULE:FUNCTION
    truth: str | None = None          #: folder of true depth files (synthetic estimator); default the input's own depth
    camera_height: float = 1.6        #: metres from the floor to the camera, scales non-metric depth
    resolution: tuple | None = None   #: output (H, W); None keeps each input's size
    split: tuple | None = (0.8, 0.1, 0.1)  #: train / val / test fractions; None writes one flat folder
    view_size: int | None = None      #: depth views' size in pixels (default from the resolution)
    nadir_view_size: int | None = None  #: the nadir view's size (default from the resolution)
    max_cap: float = 45.0             #: ``auto`` refuses a dark region reaching further from the nadir
    workers: int = 1                  #: worker processes
    clamp_negative: bool = False      #: repair negative radiance instead of skipping the file
    fill_nonfinite: float | None = None  #: repair NaN / inf radiance with this value instead of skipping
    previews: bool = True             #: write OUT/previews/NAME.png


#: Settings that decide where a file goes and its shape: a resumed run must keep them.
_FIXED = ("resolution", "split")


@dataclass(frozen=True)
class PrepareJob:
    source: str      #: input file
    rel: str         #: its path relative to the input folder
    name: str        #: output name (no extension)
    output: str      #: output file
    split: str | None


def output_name(rel: str) -> str:
    """``a/b/pano.exr`` -> ``a__b__pano``."""
    return Path(rel).with_suffix("").as_posix().replace("/", "__")


def split_for(name: str, split) -> str | None:
    """``train`` / ``val`` / ``test`` for an output name, from a hash of the name; None without a split."""
    if split is None:
        return None
    from roomlight.prior.data.splits import hash_fraction

    _, val, test = split
    f = hash_fraction(name)
    if f < test:
        return "test"
    if f < test + val:
        return "val"
    return "train"


def plan_jobs(inp, out, cfg: PrepareConfig) -> tuple[list[PrepareJob], dict[str, str]]:
    """The jobs for every panorama under ``inp``, and ``{input: reason}`` for inputs refused up front."""
    from roomlight.prior.data.splits import find_panoramas

    inp, out = Path(inp), Path(out)
    jobs, refused, seen = [], {}, {}
    for p in find_panoramas(inp):
        rel = p.relative_to(inp).as_posix()
        name = output_name(rel)
        if name in seen:
            refused[rel] = f"its output name {name!r} is taken by {seen[name]}; rename one of them"
            continue
        seen[name] = rel
        split = split_for(name, cfg.split)
        target = (out / split / f"{name}.exr") if split else (out / f"{name}.exr")
        jobs.append(PrepareJob(str(p), rel, name, str(target), split))
    return jobs, refused


# --------------------------------------------------------------------------------------------
# One file (runs in a worker process)

_CACHE: dict = {}


def _resolved(kind: str, spec: str):
    key = (kind, spec)
    if key not in _CACHE:
        if kind == "depth":
            from roomlight.datagen.prepare.estimators import resolve_estimator

            _CACHE[key] = resolve_estimator(spec)
        else:
            from roomlight.datagen.prepare.inpainters import resolve_inpainter

            _CACHE[key] = resolve_inpainter(spec)
    return _CACHE[key]


def _read_truth(job: PrepareJob, cfg: PrepareConfig, own_depth, shape) -> np.ndarray:
    if cfg.truth is None:
        if own_depth is None:
            raise InputFileError(job.source, "has no depth channel for the synthetic estimator",
                                 "keep a Z channel in the file or pass --truth DIR with NAME.exr/.npy/.png depth files")
        return own_depth
    from roomlight.core.io import read_depth, read_exr

    root = Path(cfg.truth)
    candidates = [root / Path(job.rel).with_suffix(ext) for ext in (".exr", ".npy", ".png")]
    candidates += [root / f"{job.name}{ext}" for ext in (".exr", ".npy", ".png")]
    path = next((c for c in candidates if c.is_file()), None)
    if path is None:
        raise InputFileError(job.source, f"no true depth in {root} (looked for {candidates[0].name}, .npy, .png)",
                             "add the file or leave out --truth to use the input's own Z channel")
    if path.suffix.lower() == ".exr":
        ch = read_exr(path)
        if "Z" not in ch and len(ch) != 1:
            raise InputFileError(path, f"has no Z channel (found {', '.join(sorted(ch))})",
                                 "write the true depth to channel Z")
        depth = ch["Z"] if "Z" in ch else next(iter(ch.values()))
    else:
        depth = read_depth(path)
    if depth.shape != tuple(shape):
        raise InputFileError(path, f"true depth is {depth.shape[0]}x{depth.shape[1]} but the panorama is "
                                   f"{shape[0]}x{shape[1]}", "write the truth at the panorama's size")
    if not (np.isfinite(depth).all() and (depth > 0).all()):
        raise InputFileError(path, "true depth has non-finite or non-positive values")
    return np.asarray(depth, np.float32)


def _resize(array: np.ndarray, height: int) -> np.ndarray:
    """(H, W, C) or (H, W) -> resampled to (height, 2 height) with the project's panorama resampler."""
    import torch

    from roomlight.core.geometry.resample import resize_panorama

    a = np.asarray(array, np.float64)
    chw = a.transpose(2, 0, 1) if a.ndim == 3 else a[None]
    t = resize_panorama(torch.from_numpy(np.ascontiguousarray(chw))[None], height)[0].numpy()
    return (t.transpose(1, 2, 0) if a.ndim == 3 else t[0]).astype(np.float32)


def _preview(radiance: np.ndarray, depth: np.ndarray) -> np.ndarray:
    """Radiance (auto-exposed, gamma) above the depth (log, turbo): (2H + 2, W, 3) uint8."""
    import math

    from roomlight.core.color import MIDDLE_GREY
    from roomlight.core.io.preview import colorize_depth, tonemap_gamma

    top = tonemap_gamma(radiance, exposure_stops=math.log2(MIDDLE_GREY))
    bottom = colorize_depth(depth, log=True)
    gap = np.zeros((2, top.shape[1], 3), np.uint8)
    return np.concatenate([top, gap, bottom], axis=0)


def prepare_file(job: PrepareJob, cfg: PrepareConfig, out_dir) -> dict:
    """Prepare one panorama; never raises: failures come back as ``status: skipped`` with the reason."""
    t0 = time.perf_counter()
    record = {"input": job.rel, "output": os.path.relpath(job.output, out_dir), "split": job.split}
    try:
        record.update(_prepare(job, cfg, Path(out_dir)))
        record["status"] = "written"
    except InputFileError as exc:
        # the record already names the input: keep the path only when the problem is another file's
        same = exc.path == job.source
        record.update(status="skipped", reason=(exc.problem + (f" ({exc.fix})" if exc.fix else "")) if same else str(exc))
    except RoomlightError as exc:
        record.update(status="skipped", reason=str(exc))
    except Exception as exc:  # noqa: BLE001 - one broken input must not stop the folder
        record.update(status="skipped", reason=f"{job.source}: {type(exc).__name__}: {exc}")
    record["seconds"] = round(time.perf_counter() - t0, 3)
    return record


def _prepare(job: PrepareJob, cfg: PrepareConfig, out: Path) -> dict:
    from roomlight.prior.data.splits import hash_fraction
    from roomlight.core.io import Panorama, calibrate_panorama, read_panorama, save_png, write_panorama
    from roomlight.datagen.prepare.depth import estimate_panorama_depth
    from roomlight.datagen.prepare.nadir import detect_nadir_cap, inpaint_nadir

    with warnings.catch_warnings(record=True):  # repairs come back in pano.fixes and go to the log
        warnings.simplefilter("always")
        pano = read_panorama(job.source, clamp_negative=cfg.clamp_negative, fill_nonfinite=cfg.fill_nonfinite)
    info: dict = {"source_resolution": [pano.height, pano.width], "fixes": list(pano.fixes)}
    rad = pano.radiance
    own_depth = pano.depth
    spec = _resolved("depth", cfg.depth)
    truth = _read_truth(job, cfg, own_depth, rad.shape[:2]) if spec.needs_truth else None
    if spec.keep and own_depth is None:
        raise InputFileError(job.source, "has no depth channel (Z, or A in the 4-channel layout)",
                             "estimate it: --depth moge, --depth synthetic (tests) or --depth MODULE:FUNCTION")

    # the blind spot is measured before resampling, where its rim is still sharp
    if cfg.nadir == "off":
        cap = 0.0
        info["nadir"] = {"mode": "off"}
    elif cfg.nadir == "auto":
        cap = detect_nadir_cap(rad)
        if cap > cfg.max_cap:
            raise InputFileError(job.source, f"a dark region reaches {cap:.1f} deg from the nadir (more than "
                                             f"{cfg.max_cap:g} deg): not a tripod blind spot",
                                 "pass --nadir DEG to inpaint it anyway, or --nadir off")
        info["nadir"] = {"mode": "auto", "detected_deg": round(cap, 4)}
    else:
        cap = float(cfg.nadir)
        info["nadir"] = {"mode": "given", "given_deg": cap}

    h = cfg.resolution[0] if cfg.resolution else pano.height
    if h != pano.height:
        rad = _resize(rad, h)
        own_depth = _resize(own_depth, h) if own_depth is not None else None
        truth = _resize(truth, h) if truth is not None else None
    if cap > 0:
        inpainter = _resolved("inpainter", cfg.inpainter)
        res = inpaint_nadir(rad, cap, inpainter, view_size=cfg.nadir_view_size)
        rad = res.radiance
        info["nadir"].update(res.summary(), inpainter=getattr(inpainter, "name", cfg.inpainter))
    elif cfg.nadir == "auto":
        info["nadir"]["note"] = "no blind spot found"

    if spec.keep:
        depth = own_depth
        info["depth"] = {"estimator": "keep", "note": "the input's own depth"}
    else:
        seed = int(hash_fraction(job.name) * 2**31)
        est = spec.make(truth, seed)
        res = estimate_panorama_depth(rad, est, camera_height=cfg.camera_height, view_size=cfg.view_size)
        depth = res.depth
        info["depth"] = {"estimator": cfg.depth, **res.summary()}
        if own_depth is not None and not spec.needs_truth:
            info["depth"]["note"] = "the input's own depth channel was replaced by the estimate"

    meta = {k: v for k, v in pano.metadata.items() if k not in ("split", "prepare")}
    cal = calibrate_panorama(Panorama(np.ascontiguousarray(rad, np.float32), np.asarray(depth, np.float32), meta))
    cal.metadata.update(split=job.split, source=job.rel, prepare=info)
    info["exposure_factor"] = cal.metadata["exposure_factor"]

    partial = out / PARTIAL_DIR
    partial.mkdir(parents=True, exist_ok=True)
    target = Path(job.output)
    target.parent.mkdir(parents=True, exist_ok=True)
    if cfg.previews:
        (out / PREVIEW_DIR).mkdir(exist_ok=True)
        tmp_png = partial / f"{job.name}.png"
        save_png(tmp_png, _preview(cal.radiance, cal.depth))
        os.replace(tmp_png, out / PREVIEW_DIR / f"{job.name}.png")
    tmp = partial / f"{job.name}.exr"
    # float16 tops out at 65504: a visible sun can exceed it even after calibration
    write_panorama(tmp, cal, half=float(cal.radiance.max()) < 65000.0)
    os.replace(tmp, target)
    return {"nadir": info["nadir"], "depth": info["depth"], "fixes": info["fixes"],
            "exposure_factor": info["exposure_factor"], "source_resolution": info["source_resolution"]}


def _worker_init():
    import torch

    torch.set_num_threads(1)


def _run(args):
    job, cfg, out = args
    return prepare_file(job, cfg, out)


# --------------------------------------------------------------------------------------------
# The folder


def _settings(cfg: PrepareConfig) -> dict:
    d = asdict(cfg)
    d.pop("workers")
    d["resolution"] = list(cfg.resolution) if cfg.resolution else None
    d["split"] = list(cfg.split) if cfg.split else None
    return d


def _check_resume(out: Path, settings: dict, have_outputs: bool) -> None:
    path = out / SETTINGS_NAME
    if not path.is_file():
        return
    try:
        prev = json.loads(path.read_text())
    except (OSError, json.JSONDecodeError):
        return
    differ = [k for k in _FIXED if k in prev and prev[k] != settings[k]]
    if differ and have_outputs:
        names = ", ".join(f"{k} {prev[k]} -> {settings[k]}" for k in differ)
        raise RoomlightError(f"{out} holds panoramas prepared with other settings ({names}); resuming would mix "
                             "them. Use the same --res/--split, or a new --out folder.")
    other = [k for k in settings if k not in _FIXED and k in prev and prev[k] != settings[k]]
    if other and have_outputs:
        warnings.warn(f"{out}: earlier panoramas were prepared with " +
                      ", ".join(f"{k}={prev[k]}" for k in other) + "; new ones use " +
                      ", ".join(f"{k}={settings[k]}" for k in other) + " (each file's metadata records its own)",
                      stacklevel=3)


def prepare_folder(inp, out, cfg: PrepareConfig, progress: bool = True) -> dict:
    """Prepare every panorama under ``inp`` into ``out`` (see the module docstring); returns a summary.

    Raises:
        RoomlightError: the input folder is missing or empty, the estimator or inpainter cannot be
            loaded, or ``out`` was prepared with another resolution or split. Problems with single
            inputs never raise: they are skipped and listed under ``skipped``.
    """
    inp, out = Path(inp), Path(out)
    if not inp.is_dir():
        raise InputFileError(inp, "is not a directory", "pass a folder of .exr/.hdr panoramas")
    if cfg.workers < 1:
        raise RoomlightError(f"--workers must be >= 1, got {cfg.workers}")
    if out.resolve() == inp.resolve() or inp.resolve() in out.resolve().parents:
        raise RoomlightError(f"--out {out} lies inside the input folder {inp}; pick a folder outside it")
    jobs, refused = plan_jobs(inp, out, cfg)
    if not jobs and not refused:
        raise InputFileError(inp, "contains no .exr or .hdr panorama", "pass a folder of panoramas")
    # fail before any work when the estimator or the inpainter cannot be loaded at all
    spec = _resolved("depth", cfg.depth)
    if not spec.keep and not spec.needs_truth:
        spec.make()
    if cfg.nadir != "off":
        _resolved("inpainter", cfg.inpainter)

    todo = [j for j in jobs if not Path(j.output).is_file()]
    out.mkdir(parents=True, exist_ok=True)
    shutil.rmtree(out / PARTIAL_DIR, ignore_errors=True)  # leftovers of an interrupted run
    settings = _settings(cfg)
    # any earlier output counts: with another split or size the new targets would not even collide
    earlier = any(PARTIAL_DIR not in p.relative_to(out).parts for p in out.rglob("*.exr"))
    _check_resume(out, settings, earlier)
    tmp = out / (SETTINGS_NAME + ".tmp")
    tmp.write_text(json.dumps(settings, indent=2))
    os.replace(tmp, out / SETTINGS_NAME)

    records = [{"input": rel, "status": "skipped", "reason": why} for rel, why in refused.items()]
    records += [{"input": j.rel, "output": os.path.relpath(j.output, out), "split": j.split, "status": "exists"}
                for j in jobs if j not in todo]
    bar = None
    if progress:
        from roomlight.core.progress import progress_bar

        bar = progress_bar(total=len(jobs), initial=len(jobs) - len(todo), desc="prepare", unit="pano")
    t0 = time.perf_counter()
    with open(out / LOG_NAME, "a") as log:
        stamp = time.strftime("%Y-%m-%dT%H:%M:%S")
        for r in records:
            log.write(json.dumps({**r, "time": stamp}) + "\n")

        def account(rec):
            records.append(rec)
            log.write(json.dumps({**rec, "time": time.strftime("%Y-%m-%dT%H:%M:%S")}, default=str) + "\n")
            log.flush()
            if bar is not None:
                if rec["status"] == "skipped":
                    bar.write(f"skipped {rec['input']}: {rec['reason']}")
                bar.update()

        args = [(j, cfg, str(out)) for j in todo]
        if cfg.workers > 1 and len(args) > 1:
            with ProcessPoolExecutor(cfg.workers, initializer=_worker_init) as pool:
                for rec in pool.map(_run, args):
                    account(rec)
        else:
            for a in args:
                account(_run(a))
    if bar is not None:
        bar.close()
    shutil.rmtree(out / PARTIAL_DIR, ignore_errors=True)
    written = [r for r in records if r["status"] == "written"]
    return {"written": len(written), "existing": sum(r["status"] == "exists" for r in records),
            "skipped": {r["input"]: r["reason"] for r in records if r["status"] == "skipped"},
            "wall_seconds": round(time.perf_counter() - t0, 2),
            "outputs": sorted(r["output"] for r in records if r["status"] in ("written", "exists"))}
