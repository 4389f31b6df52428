"""Speed and noise of procedural-room rendering (``roomlight synth``).

For a few generated rooms at 128x256 this renders each configuration below and compares it
with a high-spp reference of the same room (multi-jittered, max depth 8, so the PSNR counts
both the noise and the bias of cutting paths short):

- ``plain``: the reference baseline, Mitsuba ``path`` with the independent sampler, max depth 6;
- ``synth``: what ``roomlight synth`` does, multi-jittered samples per pixel, max depth 5;
- ``synth+oidn``: the same, denoised by Intel OIDN with light-source pixels kept (``--denoise``;
  only when ``pyoidn`` is importable).

Columns: render seconds per panorama with a warm kernel (median), end-to-end seconds per
panorama as the driver spends them (room generation, scene build, kernel compile or cache load,
radiance, depth, AOVs and denoising), panoramas per minute from the end-to-end time, PSNR of the
tone-mapped panorama (calibrated, x / (1 + x), gamma 2.2) against the reference, and the
99.9th-percentile luminance relative to the reference's (HDR peaks kept: 1.00).

Run: .venv/bin/python benchmarks/bench_synth.py [--rooms 3] [--height 128] [--ref-spp 4096]
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

import numpy as np

CONFIGS = [  # name, sampler, max depth, spp, denoise
    ("plain", "independent", 6, 64, False),
    ("plain", "independent", 6, 256, False),
    ("synth", "multijitter", 5, 16, False),
    ("synth", "multijitter", 5, 64, False),
    ("synth", "multijitter", 5, 144, False),
    ("synth+oidn", "multijitter", 5, 16, True),
    ("synth+oidn", "multijitter", 5, 64, True),
]


def tonemap(x):
    x = np.clip(x, 0, None)
    return (x / (1 + x)) ** (1 / 2.2)


def lum(x):
    return x @ np.array([0.2126, 0.7152, 0.0722])


def render(room, sampler, depth, spp, denoise, height, seed):
    """End-to-end for one configuration (scene build included); returns (radiance, seconds)."""
    from roomlight.datagen.synth.camera import render_aovs, render_depth, render_radiance
    from roomlight.datagen.synth.scene import build_scene

    t0 = time.perf_counter()
    scene = build_scene(room, max_depth=depth)
    rad = render_radiance(scene, room.capture, height, spp=spp, seed=seed, yaw=room.yaw, sampler=sampler)
    render_depth(scene, room.capture, height, yaw=room.yaw)
    if denoise:
        from roomlight.datagen.synth.denoise import denoise_panorama

        albedo, normal, emitter = render_aovs(scene, room.capture, height, spp=min(16, spp), seed=seed, yaw=room.yaw)
        rad = denoise_panorama(rad, albedo, normal, emitter)
    return rad, time.perf_counter() - t0, scene


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--rooms", type=int, default=3, help="rooms (seeds 0, 1, ...; one per lighting kind first)")
    ap.add_argument("--height", type=int, default=128)
    ap.add_argument("--ref-spp", type=int, default=4096)
    args = ap.parse_args()

    from roomlight.core.io.panorama import exposure_calibrate
    from roomlight.core.render.variant import ensure_variant
    from roomlight.datagen.synth.camera import render_radiance
    from roomlight.datagen.synth.denoise import denoise_available
    from roomlight.datagen.synth.rooms import generate_room
    from roomlight.datagen.synth.scene import build_scene

    variant = ensure_variant()
    configs = [c for c in CONFIGS if not c[4] or denoise_available()]
    # Rooms of different lighting first: sunny (sun patches), night (lamps), interior.
    seeds, kinds = [], []
    for seed in range(200):
        kind = generate_room(seed).lighting
        if kind not in kinds and kind in ("sunny", "night", "interior", "overcast", "dusk"):
            kinds.append(kind)
            seeds.append(seed)
        if len(seeds) == args.rooms:
            break
    rows = {c: {"warm": [], "e2e": [], "psnr": [], "peak": []} for c in configs}
    for seed in seeds:
        t0 = time.perf_counter()
        room = generate_room(seed)
        t_gen = time.perf_counter() - t0
        ref_scene = build_scene(room, max_depth=8)
        ref = render_radiance(ref_scene, room.capture, args.height, spp=args.ref_spp, seed=999, yaw=room.yaw)
        _, k = exposure_calibrate(ref)
        ref_t = tonemap(ref / k)
        ref_peak = np.percentile(lum(ref), 99.9)
        for c in configs:
            _, sampler, depth, spp, denoise = c
            img, e2e, scene = render(room, sampler, depth, spp, denoise, args.height, seed + 7)
            t1 = time.perf_counter()
            render_radiance(scene, room.capture, args.height, spp=spp, seed=seed + 8, yaw=room.yaw, sampler=sampler)
            rows[c]["warm"].append(time.perf_counter() - t1)
            rows[c]["e2e"].append(e2e + t_gen)
            rows[c]["psnr"].append(10 * np.log10(1.0 / float(((tonemap(img / k) - ref_t) ** 2).mean())))
            rows[c]["peak"].append(np.percentile(lum(img), 99.9) / ref_peak)
            print(f"  room {seed} ({room.lighting}) {c[0]} {spp} spp: {rows[c]['psnr'][-1]:.2f} dB, "
                  f"{e2e + t_gen:.2f} s end-to-end", flush=True)
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(f"\nvariant {variant}, {os.cpu_count()} cores (load average {load:.1f}); rooms {seeds} "
          f"({', '.join(kinds)}) at {args.height}x{2 * args.height}; reference {args.ref_spp} spp, max depth 8")
    print("| config | sampler | max depth | spp | render s (warm, median) | end-to-end s (median) | panoramas / min | "
          "PSNR dB (mean) | p99.9 / ref |\n|---|---|---:|---:|---:|---:|---:|---:|---:|")
    for c, r in rows.items():
        e2e = statistics.median(r["e2e"])
        print(f"| {c[0]} | {c[1]} | {c[2]} | {c[3]} | {statistics.median(r['warm']):.2f} | {e2e:.2f} | "
              f"{60 / e2e:.1f} | {np.mean(r['psnr']):.2f} | {np.mean(r['peak']):.2f} |")


if __name__ == "__main__":
    main()
