"""Speed of the visible room's albedo bound: the irradiance sum a photo fit evaluates at every step.

Compares roomlight's sum (every point-texel quantity from dot products, three (N, T) matrix products)
with the same formula written with explicit (N, T, 3) difference vectors, the form it replaced, on the
fit's sizes (512 visible points, the emitter pooled to 32 x 64 texels), forward and backward to the
light's radiance and depth. Prints a table of medians and their ratio, and the largest relative
difference of the two sums (float32: the expanded squared distance loses a few digits; in float64
tests/test_room_albedo.py checks the sum against a pair-by-pair loop to 1e-10).

Run: .venv/bin/python benchmarks/bench_room_albedo.py [--repeats 15] [--threads 1]
"""

from __future__ import annotations

import argparse
import math
import statistics
import time

import torch

from roomlight.fitting.photo.room_albedo import POOLED_HEIGHT, irradiance, pool_emitter, texel_patches


def irradiance_by_differences(radiance, depth, points, normals, pooled_height=POOLED_HEIGHT, min_cosine=0.1):
    """The same sum with explicit (N, T, 3) difference vectors."""
    rad, dep = pool_emitter(radiance, depth, pooled_height)
    pos, n, area = texel_patches(dep, min_cosine)
    diff = pos[None] - points[:, None]
    r2 = torch.maximum(diff.square().sum(-1), area[None] / (2 * math.pi))
    d = diff / r2.sqrt()[..., None]
    cos_q = (d * normals[:, None]).sum(-1).clamp_min(0)
    cos_j = (-(d * n[None])).sum(-1).clamp_min(0)
    solid = (area[None] * cos_j / r2).clamp_max(2 * math.pi)
    return (cos_q * solid) @ rad.reshape(-1, 3)


def _time(fn, radiance, depth, points, normals, repeats):
    out = []
    for i in range(repeats + 1):
        radiance.grad = depth.grad = None
        t = time.perf_counter()
        fn(radiance, depth, points, normals).square().sum().backward()
        if i:  # the first call warms up
            out.append(time.perf_counter() - t)
    return statistics.median(out)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeats", type=int, default=15)
    ap.add_argument("--threads", type=int, default=1, help="torch threads (default 1)")
    args = ap.parse_args(argv)
    torch.set_num_threads(args.threads)
    g = torch.Generator().manual_seed(0)
    radiance = (2 * torch.rand(128, 256, 3, generator=g)).requires_grad_()
    depth = (2 + torch.rand(128, 256, generator=g)).requires_grad_()
    points = 0.8 * torch.randn(512, 3, generator=g)
    normals = torch.nn.functional.normalize(torch.randn(512, 3, generator=g), dim=-1)
    with torch.no_grad():
        a = irradiance(radiance, depth, points, normals)
        b = irradiance_by_differences(radiance, depth, points, normals)
    rel = float(((a - b).abs() / b.abs().clamp_min(1e-6)).max())
    t_new = _time(irradiance, radiance, depth, points, normals, args.repeats)
    t_old = _time(irradiance_by_differences, radiance, depth, points, normals, args.repeats)
    print(f"512 points, 128 x 256 emitter pooled to {POOLED_HEIGHT} x {2 * POOLED_HEIGHT} texels, forward + backward, "
          f"{args.threads} thread(s), median of {args.repeats}; largest relative difference {rel:.1e}\n")
    print("| irradiance sum | ms | ratio |\n|---|---:|---:|")
    print(f"| explicit (N, T, 3) differences | {1000 * t_old:.1f} | 1.00 |")
    print(f"| dot products (roomlight) | {1000 * t_new:.1f} | {t_new / t_old:.2f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
