"""The end-to-end demo behind ``roomlight demo`` / ``make demo``.

Nothing is downloaded. Steps (each reported with a progress line):

1. a room: a procedural room rendered with Mitsuba (:mod:`roomlight.synth`) when that module is
   available, else the built-in example room;
2. the parallax figure: the room as a 2.5D area light and as an env map, the same probes under both;
3. a benchmark scene from the room (the paper's protocol, one material);
4. illumination fits: the prior (the bundled checkpoint, when one ships with roomlight; otherwise
   the direct 2.5D baseline, ``direct-al``) and the env-map baseline ``direct-envmap``;
5. a report: re-renders of the held-out probe under each recovered light, the metrics, and the
   recovered radiance and depth next to the truth (``report/index.html``, ``report/report.md``).
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass
from pathlib import Path

import click

from roomlight.config import StrictConfig

__all__ = ["DemoConfig", "run_demo", "bundled_prior_path"]

@dataclass
class DemoConfig(StrictConfig):
    """Sizes of the demo; the defaults finish in a few minutes on a 2-core laptop CPU."""

    out: Path = Path("roomlight-demo")
    height: int = 64          #: panorama / emitter height (width 2x)
    res: tuple[int, int] = (96, 96)  #: benchmark image size (H, W)
    iterations: int = 120     #: fitting iterations per method
    spp: int = 8              #: samples per pixel per fitting step
    gt_spp: int = 128         #: samples per pixel of the ground-truth and evaluation renders
    #: Samples per pixel of the parallax figure. The diffuse probe under the 2.5D light (thousands
    #: of emitting triangles) is noisy at 128 spp, and that noise filled the figure's difference
    #: panel, which is meant to show parallax.
    parallax_spp: int = 512
    material: str = "matte"   #: benchmark material (diffuse, matte or mirror)
    #: Room seed. 400001 is outside the seeds the bundled prior was trained and validated on
    #: (0-2399), so the demo shows the prior on a room it has never seen: a blue room lit by two
    #: windows on one side.
    seed: int = 400001


def bundled_prior_path() -> Path | None:
    """The prior checkpoint shipped inside the package, if any."""
    p = Path(__file__).parent / "assets" / "prior"
    return p if (p / "model.safetensors").is_file() else None


def _room(cfg: DemoConfig):
    """(radiance (H, W, 3), depth (H, W), description) of the demo room."""
    try:
        from roomlight.synth.dataset import render_room  # the procedural room generator
    except ImportError:
        render_room = None
    if render_room is not None:
        from roomlight.synth.denoise import denoise_available

        # The same settings as `roomlight synth`'s default: 64 spp, denoised when OIDN is installed.
        rad, depth, meta = render_room(cfg.seed, height=cfg.height, spp=64, denoise=denoise_available())
        return rad, depth, f"procedural room (seed {cfg.seed})"
    from roomlight.examples import example_room

    rad, depth = example_room(cfg.height)
    return rad, depth, "built-in example room"


def _say(step: int, total: int, text: str, t0: float) -> None:
    click.echo(f"[{step}/{total}] {text}  ({time.perf_counter() - t0:.0f} s)", err=True)


def run_demo(cfg: DemoConfig) -> dict:
    """Run every step; returns the summary also written to ``summary.json``."""
    import torch

    from roomlight.bench.builder import BenchConfig, make_benchmark
    from roomlight.bench.report import write_report
    from roomlight.bench.runner import run_benchmark
    from roomlight.inverse import fit_config
    from roomlight.io import write_panorama
    from roomlight.render.variant import ensure_variant

    out = Path(cfg.out)
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    total = 5
    variant = ensure_variant()
    _say(1, total, f"making a room on {variant}", t0)
    rad, depth, room_name = _room(cfg)
    panos = out / "panoramas"
    panos.mkdir(exist_ok=True)
    write_panorama(panos / "room.exr", (rad.numpy(), depth.numpy()), half=False, metadata={"source": room_name})

    _say(2, total, "parallax figure: 2.5D area light vs env map", t0)
    from roomlight.parallax import parallax_figure

    parallax_figure(out / "parallax", rad, depth, res=(2 * cfg.res[0], 2 * cfg.res[1]), spp=cfg.parallax_spp)

    _say(3, total, f"benchmark scene ({cfg.material}, {cfg.res[0]}x{cfg.res[1]})", t0)
    bench = out / "bench"
    make_benchmark(panos, bench, BenchConfig(n=1, seed=cfg.seed, emitter_height=cfg.height, width=cfg.res[1],
                                             height=cfg.res[0], spp=cfg.gt_spp, materials=(cfg.material,)),
                   progress=False)

    model = None
    prior = bundled_prior_path()
    if prior is not None:
        from roomlight.model import PanoVAE

        model = PanoVAE.from_pretrained(prior)
        methods = ["prior", "direct-envmap"]
    else:
        methods = ["direct-al", "direct-envmap"]
    h = model.config.resolution[0] if model is not None else cfg.height
    fc = fit_config("fast", iterations=cfg.iterations, spp=cfg.spp, direct_resolution=(h, 2 * h))
    _say(4, total, f"fitting {', '.join(methods)} ({cfg.iterations} iterations, {cfg.spp} spp)", t0)
    results = out / "results"
    run_benchmark(bench, results, methods, fc, model, eval_spp=cfg.gt_spp, progress=True,
                  model_name=f"the bundled prior ({prior})" if model is not None else None)

    _say(5, total, "report", t0)
    paths = write_report(results, out / "report", progress=False)
    table = json.loads((out / "report" / "summary.json").read_text()) if (out / "report" / "summary.json").is_file() else {}
    summary = {"variant": variant, "room": room_name, "methods": methods,
               "prior": str(prior) if prior else None, "seconds": round(time.perf_counter() - t0, 1),
               "config": {k: str(v) for k, v in cfg.__dict__.items()}, "report": {k: str(v) for k, v in paths.items()},
               "metrics": table}
    (out / "summary.json").write_text(json.dumps(summary, indent=2))
    del torch
    return summary
