"""Speed of the emitter foundation: mesh build and differentiable render + backward.

Prints a table of medians over repeated runs (first run excluded as warm-up / JIT compile).
Run: .venv/bin/python benchmarks/bench_emitter.py [--repeats N]
"""

from __future__ import annotations

import argparse
import statistics
import time

import torch


def median_time(fn, repeats: int, warmup: int = 1) -> float:
    for _ in range(warmup):
        fn()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--repeats", type=int, default=7)
    args = ap.parse_args()

    from roomlight.core.emitter.area_light import area_light_topology, build_area_light
    from roomlight.core.examples import example_room
    from roomlight.core.render.bridge import render_differentiable
    from roomlight.core.render.camera import perspective_sensor
    from roomlight.core.render.materials import material
    from roomlight.core.render.scene import EmitterScene
    from roomlight.core.render.variant import ensure_variant

    variant = ensure_variant()
    rows = []
    for h in (128, 512):
        rad, depth = example_room(h)
        area_light_topology(h, 2 * h)  # topology is cached per resolution: time the per-step work
        t = median_time(lambda: build_area_light(rad, depth), args.repeats)
        rows.append((f"mesh build {h}x{2 * h} (cached topology)", t * 1e3, "ms"))
        area_light_topology.cache_clear()
        t0 = time.perf_counter()
        area_light_topology(h, 2 * h)
        rows.append((f"topology build {h}x{2 * h} (once)", (time.perf_counter() - t0) * 1e3, "ms"))

    rad, depth = example_room(128)
    objects = {"probe": {"type": "sphere", "center": [0.3, -0.5, -1.6], "radius": 0.4, "bsdf": material("matte")}}
    sensor = perspective_sensor(target=(0.2, -0.4, -1.5), fov_deg=60, width=128, height=128)
    timings = {}
    for kind in ("mesh", "envmap"):
        es = EmitterScene(kind, (128, 256), objects=objects, sensor=sensor)
        r = rad.clone().requires_grad_()
        d = depth.clone().requires_grad_()
        seed = [0]

        def step():
            seed[0] += 2
            img = render_differentiable(es, r, d if kind == "mesh" else None, spp=16, seed=seed[0])
            img.square().mean().backward()

        timings[kind] = median_time(step, args.repeats, warmup=2)
        rows.append((f"render+backward 128x128 16spp, {kind}", timings[kind] * 1e3, "ms"))
    rows.append(("ratio mesh / envmap", timings["mesh"] / timings["envmap"], "x"))

    print(f"variant: {variant}, torch threads: {torch.get_num_threads()}, repeats: {args.repeats} (median)")
    print("| benchmark | value | unit |\n|---|---:|---|")
    for name, value, unit in rows:
        print(f"| {name} | {value:.2f} | {unit} |")


if __name__ == "__main__":
    main()
