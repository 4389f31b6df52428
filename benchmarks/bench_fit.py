"""Seconds per fitting iteration for every method, as ratios to ``direct-envmap`` in the same run.

A benchmark scene is built from the built-in example room (GT emitter 128x256). Timings are the
median seconds per iteration over ``--iterations`` steps after one warm-up step (JIT compile).
The prior methods run a default-configuration PanoVAE (13.9 M parameters, 128x256 output) with
random weights: the time per step does not depend on the weights.

Fits render only the mask's bounding box (the default); ``--compare-crop`` adds whole-frame rows.

Settings: ``cpu`` = the fast preset's per-step work at 128x128, 16 spp; ``paper`` = the paper's
fitted view, 1000x1000 at 64 spp (slow on a CPU: use --paper-iterations 2).

Run: .venv/bin/python benchmarks/bench_fit.py [--settings cpu paper] [--iterations 6] [--compare-crop]
"""

from __future__ import annotations

import argparse
import resource
import statistics
import tempfile
from pathlib import Path

import torch


def build_scene(root: Path, width: int, height: int):
    from roomlight.evaluation.bench.builder import BenchConfig, make_benchmark, read_manifest
    from roomlight.core.examples import example_room
    from roomlight.core.io import write_panorama
    from roomlight.fitting.scene import load_scene

    panos = root / "panos"
    panos.mkdir(parents=True, exist_ok=True)
    rad, depth = example_room(128)
    write_panorama(panos / "example.exr", (rad.numpy(), depth.numpy()), half=False)
    make_benchmark(panos, root / "bench", BenchConfig(n=1, width=width, height=height, spp=16, materials=("matte",)),
                   progress=False)
    manifest = read_manifest(root / "bench")
    first = manifest["scenes"][0]
    path = root / "bench" / first["scene"]
    return load_scene(path)


def time_method(scene, method, model, spp, iterations, crop=True):
    from roomlight.fitting.inverse import FitConfig, build_fitter, make_light

    cfg = FitConfig(iterations=iterations + 1, spp=spp, eval_every=10**9, crop_to_mask=crop)
    light = make_light(method, scene, cfg, model)
    fitter = build_fitter(scene, light, cfg)
    res = fitter.run(progress=False)
    times = [h["seconds"] for h in res.history if "seconds" in h][1:]  # drop the warm-up step
    return statistics.median(times)


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--settings", nargs="+", default=["cpu"], choices=["cpu", "paper"])
    ap.add_argument("--iterations", type=int, default=6)
    ap.add_argument("--paper-iterations", type=int, default=2)
    ap.add_argument("--methods", nargs="+", default=["direct-envmap", "direct-sphere", "direct-al", "prior-envmap",
                                                     "prior"])
    ap.add_argument("--compare-crop", action="store_true",
                    help="also time every method rendering the whole frame (crop_to_mask=False)")
    args = ap.parse_args()

    from roomlight.prior.model import ModelConfig, Normalization, PanoVAE
    from roomlight.core.render.variant import ensure_variant

    variant = ensure_variant()
    torch.manual_seed(0)
    model = PanoVAE(ModelConfig(), normalization=Normalization(torch.tensor([0.9, 0.8, 0.5, 0.8]),
                                                               torch.tensor([0.6, 0.6, 0.55, 0.45])))
    settings = {"cpu": (128, 128, 16, args.iterations), "paper": (1000, 1000, 64, args.paper_iterations)}
    print(f"variant {variant}, torch threads {torch.get_num_threads()}")
    print("| settings | method | s / iteration | ratio to direct-envmap |\n|---|---|---:|---:|")
    with tempfile.TemporaryDirectory() as tmp:
        for name in args.settings:
            w, h, spp, its = settings[name]
            scene = build_scene(Path(tmp) / name, w, h)
            for crop in (True, False) if args.compare_crop else (True,):
                res = {m: time_method(scene, m, model, spp, its, crop) for m in args.methods}
                base = res.get("direct-envmap")
                label = "" if crop else ", whole frame"
                for m, t in res.items():
                    ratio = f"{t / base:.2f}" if base else "-"
                    print(f"| {name} ({w}x{h}, {spp} spp{label}) | {m} | {t:.3f} | {ratio} |", flush=True)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"\npeak resident memory of this process: {peak:.0f} MiB")


if __name__ == "__main__":
    main()
