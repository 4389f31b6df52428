"""Speed and noise of procedural-room rendering (``roomlight synth``).

For a few rooms: seconds per panorama (median) at several spp, panoramas per minute, and the
noise reached: PSNR of the tone-mapped panorama (x / (1 + x), gamma 2.2, after exposure
calibration) against a high-spp reference of the same room.

Run: .venv/bin/python benchmarks/bench_synth.py [--rooms 2] [--height 128] [--ref-spp 4096]
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np


def tonemap(x):
    x = np.clip(x, 0, None)
    return (x / (1 + x)) ** (1 / 2.2)


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--rooms", type=int, default=2)
    ap.add_argument("--height", type=int, default=128)
    ap.add_argument("--spps", type=int, nargs="+", default=[16, 64, 144, 256])
    ap.add_argument("--ref-spp", type=int, default=4096)
    args = ap.parse_args()

    from roomlight.io.panorama import exposure_calibrate
    from roomlight.render.variant import ensure_variant
    from roomlight.synth.camera import render_radiance
    from roomlight.synth.rooms import generate_room
    from roomlight.synth.scene import build_scene

    variant = ensure_variant()
    rows = {s: {"t": [], "psnr": []} for s in args.spps}
    for seed in range(args.rooms):
        room = generate_room(seed)
        scene = build_scene(room)
        ref = render_radiance(scene, room.capture, args.height, spp=args.ref_spp, seed=999, yaw=room.yaw)
        _, k = exposure_calibrate(ref)
        ref_t = tonemap(ref / k)
        for spp in args.spps:
            render_radiance(scene, room.capture, args.height, spp=spp, seed=1, yaw=room.yaw)  # warm-up / JIT
            t0 = time.perf_counter()
            img = render_radiance(scene, room.capture, args.height, spp=spp, seed=seed + 7, yaw=room.yaw)
            rows[spp]["t"].append(time.perf_counter() - t0)
            mse = float(((tonemap(img / k) - ref_t) ** 2).mean())
            rows[spp]["psnr"].append(10 * np.log10(1.0 / mse))
    print(f"variant {variant}; {args.rooms} rooms at {args.height}x{2 * args.height}; reference {args.ref_spp} spp; "
          "render time only (room generation and depth excluded)")
    print("| spp | s / panorama (median) | panoramas / min | PSNR vs reference (dB, mean) |\n|---:|---:|---:|---:|")
    for spp, r in rows.items():
        t = statistics.median(r["t"])
        print(f"| {spp} | {t:.2f} | {60 / t:.1f} | {np.mean(r['psnr']):.2f} |")


if __name__ == "__main__":
    main()
