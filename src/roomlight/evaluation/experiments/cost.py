"""``roomlight experiment cost``: the paper's cost table (supplementary "Computational cost") on this machine.

Measured, each as the median of repeated runs after a warm-up run:

- **parameters** of the prior's network (``--model-preset``, the paper's by default);
- **training throughput**: full training steps (augmentation, the paper's loss, backward, AdamW,
  clipping; bf16 autocast on a GPU, as the trainer does) on random panoramas at ``train_batch``,
  in panoramas per second; the **training time** column is the paper's schedule at that rate
  (300 epochs of 2233 panoramas in batches of 32, i.e. 300 x 69 x 32 panoramas);
- **decode** time of one latent at the network's resolution (batch 1, no autograd);
- **fit time** per iteration of each inverse-rendering method on one benchmark scene (the
  built-in example room, silver matte objects, ``fit_image`` pixels square at ``fit_spp``); the
  **fit per case** column is ``paper_iterations`` (500) iterations at that rate, without the
  best-iterate checks. The prior's weights are random (time does not depend on them).

Every measurement is a part of ``OUT/parts/`` keyed by its settings and the device: a rerun
skips finished parts. ``OUT/cost.md``, ``cost.json`` and ``figures/cost.png`` hold the table.
"""

from __future__ import annotations

import json
import os
import platform
import statistics
import time
from dataclasses import dataclass
from pathlib import Path

import torch

from roomlight.core.config import StrictConfig
from roomlight.errors import RoomlightError
from roomlight.evaluation.experiments.files import atomic_json, atomic_text
from roomlight.fitting.methods import method as method_record

__all__ = ["CostConfig", "COST_PRESETS", "PAPER_SCHEDULE", "run_cost", "device_description", "median_seconds"]

#: The paper's training schedule: (epochs, panoramas, batch size).
PAPER_SCHEDULE = (300, 2233, 32)


@dataclass(frozen=True)
class CostConfig(StrictConfig):
    """What the cost table measures and how often."""

    model_preset: str = "default"     #: the prior's network (ModelConfig preset)
    train_batch: int = 8              #: batch of the timed training steps
    train_repeats: int = 2            #: timed training steps (after one warm-up step)
    decode_repeats: int = 5           #: timed decodes (after one warm-up)
    fit_image: int = 128              #: fitted view size (square); paper: 1000
    fit_spp: int = 16                 #: samples per pixel per fitting step; paper: 64
    fit_iterations: int = 4           #: timed fitting iterations (after one warm-up iteration)
    paper_iterations: int = 500       #: iterations of a whole fit, for the "fit per case" column
    methods: tuple[str, ...] = ("prior", "prior-envmap", "direct-al", "direct-sphere", "direct-envmap")
    seed: int = 0                     #: seed of the random weights and data

    def __post_init__(self):
        from roomlight.fitting.inverse.methods import METHODS
        from roomlight.prior.model.config import get_preset

        get_preset(self.model_preset)
        object.__setattr__(self, "methods", tuple(self.methods))
        bad = [m for m in self.methods if m not in METHODS]
        if bad:
            raise RoomlightError(f"cost: unknown method(s) {', '.join(bad)}; choose from {', '.join(METHODS)}")
        for name in ("train_batch", "train_repeats", "decode_repeats", "fit_image", "fit_spp", "fit_iterations",
                     "paper_iterations"):
            if getattr(self, name) < 1:
                raise RoomlightError(f"cost: {name} must be >= 1, got {getattr(self, name)}")


#: ``default``: a few minutes on a 2-core CPU; ``quick``: a smoke test; ``paper``: the paper's
#: batch and fitted view (1000 x 1000 at 64 spp: use a GPU).
COST_PRESETS = {
    "default": CostConfig(),
    "quick": CostConfig(train_batch=2, train_repeats=1, decode_repeats=2, fit_image=48, fit_spp=4, fit_iterations=2),
    "paper": CostConfig(train_batch=32, train_repeats=3, decode_repeats=20, fit_image=1000, fit_spp=64,
                        fit_iterations=5),
}


def _label(name: str) -> tuple[str, str]:
    """(family, representation) of a method for the table's first two columns."""
    return method_record(name).label


def median_seconds(fn, repeats: int, sync=lambda: None, clock=None) -> float:
    """Median time of ``fn()`` over ``repeats`` calls after one warm-up call.

    ``clock`` defaults to wall time (``time.perf_counter``); ``time.process_time`` gives the
    CPU seconds of all the process's threads instead, which a busy machine inflates far less.
    """
    clock = clock or time.perf_counter
    fn()
    sync()
    times = []
    for _ in range(repeats):
        t0 = clock()
        fn()
        sync()
        times.append(clock() - t0)
    return statistics.median(times)


def _timed(fn, repeats: int, sync) -> tuple[float, float]:
    """(median wall seconds, median CPU seconds) of ``fn()``, each call timed by both clocks."""
    walls, cpus = [], []

    def call():
        w0, c0 = time.perf_counter(), time.process_time()
        fn()
        sync()
        walls.append(time.perf_counter() - w0)
        cpus.append(time.process_time() - c0)

    median_seconds(call, repeats, sync)
    return statistics.median(walls[1:]), statistics.median(cpus[1:])  # the first call is the warm-up


def _cpu_name() -> str:
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def device_description(device: str) -> dict:
    """The hardware a measurement ran on: torch device name, threads, Mitsuba variant."""
    from roomlight.core.render.variant import mitsuba

    variant = mitsuba().variant()
    if device == "cuda":
        name = torch.cuda.get_device_name(0)
    else:
        threads = torch.get_num_threads()
        name = f"{_cpu_name()}, {threads} torch thread{'s' if threads != 1 else ''}"
    return {"device": device, "name": name, "mitsuba_variant": variant, "torch": torch.__version__,
            "load_average": os.getloadavg()[0] if hasattr(os, "getloadavg") else None}


def _model(cfg: CostConfig, device: str):
    from roomlight.prior.model import Normalization, PanoVAE, get_preset

    torch.manual_seed(cfg.seed)
    norm = Normalization(mean=(0.9, 0.8, 0.5, 1.0), std=(0.6, 0.6, 0.55, 0.45))
    return PanoVAE(get_preset(cfg.model_preset), norm).to(device)


def _sync(device: str):
    return torch.cuda.synchronize if device == "cuda" else (lambda: None)


def measure_model(cfg: CostConfig, device: str) -> dict:
    """Parameters, training throughput (panoramas / s) and decode time (ms) of the prior's network."""
    from roomlight.prior.data import augment_batch
    from roomlight.prior.losses import vae_loss

    model = _model(cfg, device)
    params = sum(p.numel() for p in model.parameters())
    h, w = model.config.resolution
    g = torch.Generator().manual_seed(cfg.seed + 1)
    rad = (torch.rand(cfg.train_batch, 3, h, w, generator=g).pow(4) * 20).to(device)
    dep = (torch.rand(cfg.train_batch, 1, h, w, generator=g) * 4 + 1).to(device)
    opt = torch.optim.AdamW(model.parameters(), lr=2e-4, betas=(0.9, 0.99), weight_decay=0.01)
    aug = torch.Generator().manual_seed(cfg.seed + 2)
    gen = torch.Generator(device=device).manual_seed(cfg.seed + 3)
    amp = device == "cuda"

    def step():
        model.train()
        r, d = augment_batch(rad, dep, aug)
        x = model.normalization.normalize(r, d)
        with torch.autocast(device_type=device, dtype=torch.bfloat16, enabled=amp):
            x_hat, post = model(x, True, gen)
        loss = vae_loss(x_hat.float(), x, post.mean.float(), post.logvar.float(), 500, model.normalization,
                        target_radiance=r)["total"]
        opt.zero_grad(set_to_none=True)
        loss.backward()
        torch.nn.utils.clip_grad_norm_(model.parameters(), 10.0)
        opt.step()

    sync = _sync(device)
    t_step, cpu_step = _timed(step, cfg.train_repeats, sync)
    model.eval()
    z = torch.randn(1, model.config.latent_dim, generator=g).to(device)

    def decode():
        with torch.no_grad():
            model.decode(z)

    t_decode, cpu_decode = _timed(decode, cfg.decode_repeats, sync)
    epochs, n, batch = PAPER_SCHEDULE
    schedule = epochs * (n // batch) * batch
    rate = cfg.train_batch / t_step
    return {"parameters": int(params), "resolution": [h, w], "train_step_seconds": t_step,
            "train_step_cpu_seconds": cpu_step, "train_batch": cfg.train_batch, "panoramas_per_second": rate,
            "paper_schedule_panoramas": schedule, "paper_schedule_hours": schedule / rate / 3600.0,
            "paper_schedule_cpu_hours": schedule / cfg.train_batch * cpu_step / 3600.0,
            "decode_ms": 1000.0 * t_decode, "decode_cpu_ms": 1000.0 * cpu_decode, "amp_bf16": amp}


def _bench_scene(root: Path, cfg: CostConfig):
    from roomlight.evaluation.bench.builder import BenchConfig, make_benchmark, read_manifest
    from roomlight.core.examples import example_room
    from roomlight.core.io import write_panorama
    from roomlight.fitting.scene import load_scene

    bench = root / f"scene-{cfg.fit_image}"
    if not (bench / "manifest.json").is_file():
        panos = root / "panos"
        panos.mkdir(parents=True, exist_ok=True)
        rad, depth = example_room(128)
        write_panorama(panos / "example.exr", (rad.numpy(), depth.numpy()), half=False)
        make_benchmark(panos, bench, BenchConfig(n=1, seed=cfg.seed, width=cfg.fit_image, height=cfg.fit_image,
                                                 spp=16, materials=("matte",)), progress=False)
    first = read_manifest(bench)["scenes"][0]
    return load_scene(bench / first["scene"])


def measure_fit(scene, method: str, cfg: CostConfig, model) -> dict:
    """Median wall and CPU seconds per fitting iteration of ``method`` (:meth:`Fitter.step`:
    render, loss, backward, Adam), after one warm-up iteration."""
    from roomlight.fitting.inverse import FitConfig, build_fitter, make_light

    fcfg = FitConfig(iterations=cfg.fit_iterations + 1, spp=cfg.fit_spp, seed=cfg.seed)
    fitter = build_fitter(scene, make_light(method, scene, fcfg, model), fcfg)
    it = iter(range(cfg.fit_iterations + 1))
    wall, cpu = _timed(lambda: fitter.step(next(it)), cfg.fit_iterations, lambda: None)
    return {"method": method, "seconds_per_iteration": wall, "cpu_seconds_per_iteration": cpu,
            "iterations_timed": cfg.fit_iterations, "fit_minutes": wall * cfg.paper_iterations / 60.0,
            "fit_cpu_minutes": cpu * cfg.paper_iterations / 60.0, "fit_image": cfg.fit_image,
            "fit_spp": cfg.fit_spp}


def _part(out: Path, name: str, key: dict, compute) -> dict:
    """A finished measurement from ``OUT/parts/<name>.json`` when its key matches, else computed and stored."""
    f = out / "parts" / f"{name}.json"
    if f.is_file():
        old = json.loads(f.read_text())
        if old.get("key") == key:
            return old["value"]
    value = compute()
    f.parent.mkdir(parents=True, exist_ok=True)
    atomic_json(f, {"key": key, "value": value})
    return value


def run_cost(out_dir, cfg: CostConfig = CostConfig(), device: str = "auto") -> dict:
    """Measure everything (finished parts are reused) and write the table; returns the summary.

    Args:
        device: ``cuda``, ``cpu`` or ``auto`` (CUDA when torch can use it).
    """
    if device == "auto":
        device = "cuda" if torch.cuda.is_available() else "cpu"
    if device == "cuda" and not torch.cuda.is_available():
        raise RoomlightError("cost: --device cuda, but torch sees no usable CUDA device")
    from roomlight.core.render.variant import ensure_variant

    # Mitsuba on the same side as torch: its CPU backend even where a GPU exists, and the reverse
    ensure_variant("llvm_ad_rgb" if device == "cpu" else "cuda_ad_rgb")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    dev = device_description(device)
    key = {"config": cfg.to_dict(), "device": {k: dev[k] for k in ("device", "name", "mitsuba_variant")}}
    model_part = _part(out, "model", key, lambda: measure_model(cfg, device))
    made: dict = {}  # the scene and the model, built only when a fit must be measured

    def fit(method: str) -> dict:
        if "scene" not in made:
            made["scene"] = _bench_scene(out / "scene", cfg)
            made["model"] = _model(cfg, device).eval()
        return measure_fit(made["scene"], method, cfg, made["model"])

    fits = {m: _part(out, f"fit-{m}", {**key, "method": m}, lambda m=m: fit(m)) for m in cfg.methods}
    summary = {"device": dev, "settings": cfg.to_dict(), "model": model_part, "fits": fits,
               "wall_seconds": time.perf_counter() - t0}
    text = cost_markdown(summary)
    atomic_json(out / "cost.json", summary)
    _figure(out, summary)
    atomic_text(out / "cost.md", text)
    summary["markdown"] = text
    return summary


def cost_markdown(summary: dict) -> str:
    """The cost table in the paper's layout (one row per method) with its settings. Each time is
    given as wall time and, in brackets, the CPU time of all the process's threads."""
    m, s, dev = summary["model"], summary["settings"], summary["device"]
    h, w = m["resolution"]
    epochs, n, batch = PAPER_SCHEDULE
    lines = ["# Cost of the priors on this machine", "",
             f"Device: **{dev['name']}** (torch {dev['torch']}, Mitsuba `{dev['mitsuba_variant']}`"
             + (f", load average {dev['load_average']:.1f} when it started" if dev.get("load_average") is not None
                else "") + ").", "",
             "| Method | Emitter | Params (M) | Training (h) | Decode (ms) | Fit (s / iteration) | Fit per case (min) |",
             "|---|---|---:|---:|---:|---:|---:|"]

    def both(wall: float, cpu: float | None, fmt: str) -> str:
        return f"{wall:{fmt}}" + ("" if cpu is None else f" ({cpu:{fmt}})")

    for method, f in summary["fits"].items():
        label, emitter = _label(method)
        prior = method_record(method).model == "prior"  # the network, training and decode columns are its
        cells = [label, emitter, f"{m['parameters'] / 1e6:.3g}" if prior else "–",
                 both(m["paper_schedule_hours"], m.get("paper_schedule_cpu_hours"), ".1f") if prior else "–",
                 both(m["decode_ms"], m.get("decode_cpu_ms"), ".1f") if prior else "–",
                 both(f["seconds_per_iteration"], f.get("cpu_seconds_per_iteration"), ".3f"),
                 both(f["fit_minutes"], f.get("fit_cpu_minutes"), ".1f")]
        lines.append("| " + " | ".join(cells) + " |")
    lines += ["",
              f"Network: the `{s['model_preset']}` preset ({m['parameters']:,} parameters, {h}×{w}). Training: "
              f"{m['panoramas_per_second']:.2f} panoramas/s measured (median of {s['train_repeats']} full steps at "
              f"batch {m['train_batch']}{', bf16 autocast' if m.get('amp_bf16') else ''}); the column is the "
              f"paper's schedule ({epochs} epochs × {n // batch} batches of {batch} = "
              f"{m['paper_schedule_panoramas']:,} panoramas) at that rate. Decode: one latent, batch 1, "
              f"median of {s['decode_repeats']}. Fits: the example room's benchmark scene, silver matte, "
              f"{s['fit_image']}×{s['fit_image']} pixels at {s['fit_spp']} spp per step (paper: 1000×1000 at 64), "
              f"median of {s['fit_iterations']} iterations (render, loss, backward, Adam) after a warm-up; the last "
              f"column is {s['paper_iterations']} iterations at that rate (best-iterate checks not included). The "
              "smoothness baselines optimise 128×256 maps and have no network.",
              "Times: wall clock, and in brackets the CPU time of all the process's threads. On a machine shared "
              "with other work the wall time measures the sharing; the CPU time is close to what the same work "
              "costs on cores of its own (it ignores waiting, and sums the threads of multi-threaded parts).",
              f"Wall time of this call: {summary['wall_seconds']:.0f} s."]
    return "\n".join(lines) + "\n"


def _figure(out: Path, summary: dict) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fits = summary["fits"]
    names = list(fits)
    vals = [fits[k]["seconds_per_iteration"] for k in names]
    fig, ax = plt.subplots(figsize=(1.4 * len(names) + 2, 3.0))
    ax.bar(range(len(names)), vals, color=["crimson" if k.startswith("prior") else "steelblue" for k in names])
    ax.set_xticks(range(len(names)))
    ax.set_xticklabels(names, rotation=30, fontsize=8)
    ax.set_ylabel("seconds per fitting iteration")
    ax.set_title(f"{summary['device']['name']}", fontsize=8)
    for i, v in enumerate(vals):
        ax.annotate(f"{v:.2f}", (i, v), ha="center", va="bottom", fontsize=7)
    fig.tight_layout()
    path = out / "figures" / "cost.png"
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(".cost.tmp.png")
    fig.savefig(tmp, dpi=110)
    plt.close(fig)
    tmp.replace(path)
    return path

