"""The ``roomlight synth`` driver: procedural rooms rendered into a panorama dataset.

Sample ``seed`` is the room ``generate_room(seed)`` path-traced from its capture point into an
equirectangular panorama (radiance, Mitsuba ``path`` integrator through
:mod:`roomlight.datagen.synth.camera`) with exact radial depth (ray intersection at pixel centres). The
radiance is exposure-calibrated (unit log-average luminance, docs/conventions.md) and written as
``SPLIT/room-SEED.exr`` (R, G, B half — float32 when a value exceeds the half range — + Z float32, metres) with metadata: the calibration factor,
seed, split, resolution, spp and a summary of the room.

Splits are seed ranges: with ``n`` samples starting at ``seed0``, the last 10 % of the range are
``test``, the 10 % before them ``val``, the rest ``train`` (at least one of each when n >= 3).
Shards partition the seed range by ``seed mod n_shards``. Finished files are skipped, so an
interrupted run continues where it stopped; files are written to a temporary name and renamed,
so a kill never leaves a half-written sample.
"""

from __future__ import annotations

import json
import math
import os
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch

from roomlight.core.color import MIDDLE_GREY, luminance_np
from roomlight.errors import RoomlightError

__all__ = [
    "SynthConfig",
    "contact_sheet",
    "generate_dataset",
    "render_room",
    "sample_path",
    "split_of",
    "write_stats",
]


@dataclass(frozen=True)
class SynthConfig:
    """Settings of ``roomlight synth``."""

    n: int = 500                  #: number of samples (seeds seed0 .. seed0 + n - 1)
    seed0: int = 0                #: first seed
    height: int = 128             #: panorama height (width 2x)
    spp: int = 144                #: samples per pixel of the path tracer (a perfect square)
    shard: tuple[int, int] = (0, 1)  #: (i, n): this process renders seeds with seed % n == i
    workers: int = 1              #: worker processes
    nadir_cap: float = 0.0        #: simulate a tripod blind spot: black cap of this polar angle (deg)
    denoise: bool = False         #: denoise with Intel OIDN (pyoidn), light sources kept unbiased
    scheduler: str | None = None  #: a Dask scheduler address: render on its workers instead (see roomlight.core.cluster)


def split_of(seed: int, seed0: int, n: int) -> str:
    """``train``, ``val`` or ``test`` for a seed of the range [seed0, seed0 + n)."""
    k = seed - seed0
    n_test = max(1, round(0.1 * n)) if n >= 3 else 0
    n_val = max(1, round(0.1 * n)) if n >= 3 else 0
    if k >= n - n_test:
        return "test"
    if k >= n - n_test - n_val:
        return "val"
    return "train"


def sample_path(out: Path, seed: int, seed0: int, n: int) -> Path:
    return Path(out) / split_of(seed, seed0, n) / f"room-{seed:06d}.exr"


def _room_summary(room) -> dict:
    lights = [lt for lt in room.lights if getattr(lt, "on", True)]
    return {"shell": room.shell, "room_type": room.room_type, "lighting": room.lighting,
            "ceiling_height": round(float(room.height), 4), "capture": [round(float(c), 4) for c in room.capture],
            "yaw": round(float(room.yaw), 6), "lights_on": len(lights),
            "light_kinds": sorted({lt.kind for lt in lights}), "windows": len(room.windows),
            "doors": len(room.doors), "furniture": len(room.furniture), "generator": room.version}


def render_room(seed: int, height: int = 128, spp: int = 128, nadir_cap: float = 0.0, denoise: bool = False):
    """Render one sample: (radiance (H, W, 3) calibrated torch, depth (H, W) metres, metadata).

    With ``denoise`` the path-traced radiance is denoised by Intel OIDN with first-hit albedo
    and normals; pixels of light sources keep their Monte Carlo values
    (:mod:`roomlight.datagen.synth.denoise`).
    """
    from roomlight.core.io.panorama import exposure_calibrate
    from roomlight.datagen.synth.camera import render_depth, render_radiance
    from roomlight.datagen.synth.rooms import generate_room
    from roomlight.datagen.synth.scene import build_scene

    room = generate_room(int(seed))
    scene = build_scene(room)
    rad = render_radiance(scene, room.capture, height=height, spp=spp, seed=int(seed), yaw=room.yaw)
    depth = render_depth(scene, room.capture, height=height, yaw=room.yaw)
    denoiser = None
    if denoise:
        from roomlight.datagen.synth.camera import render_aovs
        from roomlight.datagen.synth.denoise import denoise_panorama, denoiser_version

        albedo, normal, emitter = render_aovs(scene, room.capture, height=height, spp=min(16, spp), seed=int(seed),
                                              yaw=room.yaw)
        rad = denoise_panorama(rad, albedo, normal, emitter)
        denoiser = denoiser_version() + " (hdr, albedo + normal, light sources kept)"
    if not np.isfinite(depth).all() or (depth <= 0).any():
        raise RoomlightError(f"room {seed}: a panorama ray escaped the room (depth not finite); this is a generator bug")
    rad = np.clip(rad, 0.0, None)
    if nadir_cap > 0:
        theta = (np.arange(height) + 0.5) / height * 180.0
        rad[theta > 180.0 - nadir_cap] = 0.0
    cal, factor = exposure_calibrate(rad)
    meta = {"seed": int(seed), "exposure_factor": float(factor), "spp": int(spp), "resolution": [height, 2 * height],
            "room": _room_summary(room), "nadir_cap_deg": float(nadir_cap)}
    if denoiser:
        meta["denoiser"] = denoiser
    return torch.from_numpy(np.ascontiguousarray(cal, np.float32)), torch.from_numpy(depth.astype(np.float32)), meta


def _render_to_file(args) -> tuple[int, str | None, float]:
    seed, path, cfg_n, seed0, height, spp, nadir_cap, threads, denoise = args
    from roomlight.core.io import write_panorama

    if threads:
        import drjit as dr

        dr.set_thread_count(threads)
    t0 = time.perf_counter()
    try:
        rad, depth, meta = render_room(seed, height, spp, nadir_cap, denoise)
        meta["split"] = split_of(seed, seed0, cfg_n)
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(path.stem + ".partial.exr")
        # float16 tops out at 65504: a visible sun can exceed it even after calibration
        half = float(rad.max()) < 65000.0
        write_panorama(tmp, (rad.numpy(), depth.numpy()), half=half, metadata=meta)
        os.replace(tmp, path)
        return seed, None, time.perf_counter() - t0
    except Exception as exc:  # noqa: BLE001 - reported per sample; the run goes on
        return seed, f"{type(exc).__name__}: {exc}", time.perf_counter() - t0


def generate_dataset(out, cfg: SynthConfig, progress: bool = True) -> dict:
    """Render the (shard of the) dataset into ``out``; returns a run summary."""
    out = Path(out)
    i, k = cfg.shard
    if not (0 <= i < k):
        raise RoomlightError(f"--shard {i}/{k}: need 0 <= i < n")
    if cfg.height < 4 or cfg.spp < 1 or cfg.n < 1:
        raise RoomlightError("synth: --n, --spp must be >= 1 and the height >= 4")
    if math.isqrt(cfg.spp) ** 2 != cfg.spp:
        # the stratified (multi-jittered) sampler draws a square number of samples per pixel
        raise RoomlightError(f"synth: --spp must be a perfect square (e.g. 64, 144, 256), got {cfg.spp}")
    if cfg.denoise:
        from roomlight.datagen.synth.denoise import denoiser_version

        denoiser_version()  # fail before any work when pyoidn is missing
    seeds = [s for s in range(cfg.seed0, cfg.seed0 + cfg.n) if s % k == i]
    todo = [s for s in seeds if not sample_path(out, s, cfg.seed0, cfg.n).is_file()]
    out.mkdir(parents=True, exist_ok=True)
    settings = {"n": cfg.n, "seed0": cfg.seed0, "height": cfg.height, "spp": cfg.spp, "nadir_cap": cfg.nadir_cap,
                "denoise": cfg.denoise}
    _check_resume(out, settings, len(seeds) - len(todo))
    tmp = out / "synth.json.tmp"
    tmp.write_text(json.dumps(settings, indent=2))
    os.replace(tmp, out / "synth.json")
    threads = max(1, (os.cpu_count() or 1) // cfg.workers) if cfg.workers > 1 else 0
    jobs = [(s, str(sample_path(out, s, cfg.seed0, cfg.n)), cfg.n, cfg.seed0, cfg.height, cfg.spp, cfg.nadir_cap,
             threads, cfg.denoise) for s in todo]
    failures: dict[int, str] = {}
    seconds = []
    bar = None
    if progress:
        from roomlight.core.progress import progress_bar

        bar = progress_bar(total=len(seeds), initial=len(seeds) - len(todo), desc="synth", unit="pano")
    t0 = time.perf_counter()
    if cfg.scheduler is not None:
        from roomlight.core.cluster import map_unordered

        for seed, err, sec in map_unordered(_render_to_file, jobs, cfg.scheduler):
            _account(seed, err, sec, failures, seconds, bar)
    elif cfg.workers > 1 and len(jobs) > 1:
        with ProcessPoolExecutor(cfg.workers) as pool:
            results = pool.map(_render_to_file, jobs)
            for seed, err, sec in results:
                _account(seed, err, sec, failures, seconds, bar)
    else:
        for job in jobs:
            _account(*_render_to_file(job), failures, seconds, bar)
    if bar:
        bar.close()
    wall = time.perf_counter() - t0
    summary = {"rendered": len(jobs) - len(failures), "skipped_existing": len(seeds) - len(todo),
               "failed": {str(s): e for s, e in failures.items()}, "wall_seconds": round(wall, 2),
               "panoramas_per_minute": round(60.0 * (len(jobs) - len(failures)) / wall, 2) if jobs and wall > 0 else None,
               "median_seconds_per_panorama": round(float(np.median(seconds)), 3) if seconds else None}
    return summary


#: Settings that decide which file a seed goes to and its shape: resuming must keep them.
_RESUME_FIXED = ("n", "seed0", "height")


def _check_resume(out: Path, settings: dict, finished: int) -> None:
    """Refuse to add to a folder rendered with other split/shape settings (it would silently mix
    resolutions or move seeds between splits); settings that only change noise are allowed."""
    prev_path = out / "synth.json"
    if not prev_path.is_file():
        return
    try:
        prev = json.loads(prev_path.read_text())
    except (OSError, json.JSONDecodeError):
        return
    differ = [k for k in _RESUME_FIXED if k in prev and prev[k] != settings[k]]
    if differ and finished == 0 and not any(out.glob("*/room-*.exr")):
        return  # nothing rendered yet under the old settings
    if differ:
        names = ", ".join(f"{k} {prev[k]} -> {settings[k]}" for k in differ)
        raise RoomlightError(
            f"{out} holds a dataset rendered with other settings ({names}); resuming would mix them. "
            "Use the same --n/--seed/--res, or a new --out folder.")
    noisy = [k for k in ("spp", "denoise", "nadir_cap") if k in prev and prev[k] != settings[k]]
    if noisy:
        import warnings

        warnings.warn(f"{out}: earlier samples were rendered with " +
                      ", ".join(f"{k}={prev[k]}" for k in noisy) + "; new ones use " +
                      ", ".join(f"{k}={settings[k]}" for k in noisy) + " (each file's metadata records its own)",
                      stacklevel=2)


def _account(seed, err, sec, failures, seconds, bar):
    if err:
        failures[seed] = err
        if bar:
            bar.write(f"room {seed} failed: {err}")
    else:
        seconds.append(sec)
    if bar:
        bar.update()


def _files(out: Path) -> list[Path]:
    return sorted(p for p in Path(out).glob("*/room-*.exr") if ".partial" not in p.name)


def write_stats(out, files=None) -> dict:
    """``stats.json`` over every sample in ``out``: luminance percentiles, dynamic range, depth range.

    ``files`` lists the samples (default: ``out/*/room-*.exr``); a sample's split is its folder's name."""
    from roomlight.core.io import read_panorama

    lums, depths, dr_stops, factors, counts = [], [], [], [], {}
    for p in (_files(out) if files is None else [Path(f) for f in files]):
        pano = read_panorama(p)
        y = luminance_np(pano.radiance)
        lums.append(np.random.default_rng(0).choice(y.ravel(), size=min(4096, y.size), replace=False))
        depths.append([float(pano.depth.min()), float(pano.depth.max())])
        pos = y[y > 0]
        dr_stops.append(float(np.log2(pos.max() / np.percentile(pos, 1))) if pos.size else 0.0)
        factors.append(float(pano.metadata.get("exposure_factor", float("nan"))))
        split = p.parent.name
        counts[split] = counts.get(split, 0) + 1
    if not lums:
        raise RoomlightError(f"{out}: no samples to summarise")
    y = np.concatenate(lums)
    d = np.asarray(depths)
    stats = {"samples": int(sum(counts.values())), "splits": counts,
             "luminance_percentiles": {str(q): float(np.percentile(y, q)) for q in (1, 5, 25, 50, 75, 95, 99, 99.9)},
             "luminance_max": float(y.max()),
             "dynamic_range_stops": {"median": float(np.median(dr_stops)), "min": float(np.min(dr_stops)),
                                     "max": float(np.max(dr_stops))},
             "depth_m": {"min": float(d[:, 0].min()), "median_min": float(np.median(d[:, 0])),
                         "median_max": float(np.median(d[:, 1])), "max": float(d[:, 1].max())},
             "exposure_factor": {"median": float(np.nanmedian(factors)), "min": float(np.nanmin(factors)),
                                 "max": float(np.nanmax(factors))}}
    (Path(out) / "stats.json").write_text(json.dumps(stats, indent=2))
    return stats


def contact_sheet(out, count: int = 24, columns: int = 4, files=None) -> Path:
    """``contact_sheet.png``: tone-mapped radiance of the first ``count`` samples.

    Samples are calibrated to unit log-average luminance; the sheet maps that average to
    photographic middle grey (0.18, i.e. -2.47 stops) before clipping and gamma 2.2, as a camera's
    auto-exposure would, so walls are not washed out and only light sources saturate. ``files``
    lists the samples (default: ``out/*/room-*.exr``)."""
    from roomlight.core.io import read_panorama, save_png
    from roomlight.core.io.preview import tonemap_gamma

    files = (_files(out) if files is None else [Path(f) for f in files])[:count]
    if not files:
        raise RoomlightError(f"{out}: no samples for a contact sheet")
    tiles = [tonemap_gamma(read_panorama(p).radiance, exposure_stops=math.log2(MIDDLE_GREY)) for p in files]
    h, w, _ = tiles[0].shape
    rows = math.ceil(len(tiles) / columns)
    sheet = np.zeros((rows * (h + 2), columns * (w + 2), 3), np.uint8)
    for k, t in enumerate(tiles):
        r, c = divmod(k, columns)
        if t.shape == (h, w, 3):
            sheet[r * (h + 2):r * (h + 2) + h, c * (w + 2):c * (w + 2) + w] = t
    path = Path(out) / "contact_sheet.png"
    save_png(path, sheet)
    return path
