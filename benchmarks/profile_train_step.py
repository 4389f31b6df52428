"""Where a CPU training step's time goes: phases (augmentation, forward, loss, backward, optimiser)
and operator families (convolutions, spherical padding, normalisation, activations, ...), plus
the data loader's time per batch from the packed cache.

Run: .venv/bin/python benchmarks/profile_train_step.py [--preset lite] [--batch 32] [--steps 6]
                                                        [--threads 2] [--data data/rooms64]

Prints two Markdown tables (phases by wall time, operator families by self CPU time, both as
shares of a step) from torch.profiler over ``--steps`` steps after two warm-up steps.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import torch

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_model import make_model, train_step_fn  # noqa: E402

#: Operator families, matched in order against the profiler's op names (first match wins).
FAMILIES = (
    ("convolution", ("conv", "mkldnn", "onednn")),
    ("spherical padding (slice copies, flips)", ("copy_", "flip", "slice", "new_empty", "empty", "as_strided")),
    ("normalisation (GroupNorm / AdaGN)", ("group_norm", "native_group_norm", "batch_norm")),
    ("activations (SiLU)", ("silu",)),
    ("resampling (tilt augmentation, upsampling)", ("grid_sampler", "upsample", "index", "gather", "repeat")),
    ("optimiser (AdamW, clipping)", ("_foreach", "addcdiv", "lerp", "sqrt", "norm")),
    ("element-wise arithmetic", ("add", "mul", "sub", "div", "exp", "log", "abs", "pow", "neg", "clamp",
                                 "where", "sum", "mean", "max", "min")),
)


def family(name: str) -> str:
    n = name.lower()
    for fam, keys in FAMILIES:
        if any(k in n for k in keys):
            return fam
    return "other"


def loader_seconds(data: str, preset: str, batch: int, batches: int = 8) -> float | None:
    """Median seconds per batch of the training loader over the packed cache (None without data)."""
    from roomlight.prior.train import Trainer, get_train_preset

    if not data or not Path(data).is_dir():
        return None
    import tempfile

    cfg = get_train_preset(preset).replace(batch_size=batch, num_workers=0, progress=False)
    with tempfile.TemporaryDirectory() as tmp:
        t = Trainer(cfg, data, tmp, device="cpu", note=lambda m: None)
        from torch.utils.data import DataLoader

        from roomlight.prior.data import collate_panoramas

        loader = DataLoader(t.train_set, batch_sampler=t.sampler, collate_fn=collate_panoramas, num_workers=0)
        it, times = iter(loader), []
        next(it)
        for _ in range(batches):
            t0 = time.perf_counter()
            next(it)
            times.append(time.perf_counter() - t0)
        t.close()
    return statistics.median(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--preset", default="lite")
    ap.add_argument("--batch", type=int, default=32)
    ap.add_argument("--steps", type=int, default=6)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--data", default="", help="a data folder, to time the loader too")
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    model = make_model(args.preset, "cpu")
    step = train_step_fn(model, args.batch, "cpu", amp=False)
    step()
    step()
    with torch.profiler.profile(activities=[torch.profiler.ProfilerActivity.CPU]) as prof:
        t0 = time.perf_counter()
        for _ in range(args.steps):
            step()
        wall = (time.perf_counter() - t0) / args.steps
    events = prof.key_averages()
    phases = {e.key: e.cpu_time_total / 1e6 / args.steps for e in events if e.key.startswith("phase: ")}
    fam: dict[str, float] = {}
    for e in events:
        if e.key.startswith("phase: ") or e.key.startswith("ProfilerStep"):
            continue
        fam[family(e.key)] = fam.get(family(e.key), 0.0) + e.self_cpu_time_total / 1e6 / args.steps
    total_self = sum(fam.values())
    h, w = model.config.resolution
    print(f"preset {args.preset} {h}x{w}, batch {args.batch}, {args.threads} threads: {wall * 1e3:.0f} ms per step "
          f"(profiled; {args.batch / wall:.1f} panoramas/s)")
    print("\n| phase | ms per step | share |\n|---|---:|---:|")
    for k, v in sorted(phases.items(), key=lambda kv: -kv[1]):
        print(f"| {k[7:]} | {v * 1e3:.0f} | {v / wall:.0%} |")
    print("\n| operator family (self CPU time) | ms per step | share |\n|---|---:|---:|")
    for k, v in sorted(fam.items(), key=lambda kv: -kv[1]):
        print(f"| {k} | {v * 1e3:.0f} | {v / total_self:.0%} |")
    top = sorted((e for e in events if not e.key.startswith(("phase: ", "ProfilerStep"))),
                 key=lambda e: -e.self_cpu_time_total)[:12]
    print("\n| operator | family | ms per step |\n|---|---|---:|")
    for e in top:
        print(f"| `{e.key}` | {family(e.key)} | {e.self_cpu_time_total / 1e3 / args.steps:.0f} |")
    sec = loader_seconds(args.data, args.preset, args.batch)
    if sec is not None:
        print(f"\ndata loading from the packed cache: {sec * 1e3:.1f} ms per batch of {args.batch} "
              f"({sec / wall:.1%} of a step)")


if __name__ == "__main__":
    main()
