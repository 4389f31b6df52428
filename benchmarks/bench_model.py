"""Speed and memory of the prior: decode latency, training throughput, peak training memory.

- decode latency of the paper's model at 128 x 256, batch 1 and 32 (target batch 1 <= 120 ms
  with 2 CPU threads);
- training throughput (panoramas / s) of full training steps (forward, the paper's loss,
  backward, AdamW) at batch 32, for the default model and the small/tiny presets;
- peak memory of a training step at batch 32 (CPU: the process's peak resident set size, in a
  fresh subprocess, minus its size before the step; CUDA: torch.cuda.max_memory_allocated).

Prints a Markdown table of medians (first runs excluded as warm-up).
Run: .venv/bin/python benchmarks/bench_model.py [--threads 2] [--repeats 5] [--device cpu|cuda] [--decode-only]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time

import torch


def median_time(fn, repeats: int, warmup: int = 1, sync=lambda: None) -> float:
    for _ in range(warmup):
        fn()
    sync()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        sync()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def make_model(preset: str, device: str):
    from roomlight.model import Normalization, PanoVAE, get_preset

    torch.manual_seed(0)
    norm = Normalization(mean=(0.9, 0.8, 0.5, 1.0), std=(0.6, 0.6, 0.55, 0.45))
    return PanoVAE(get_preset(preset), norm).to(device)


def fake_batch(model, batch: int, device: str):
    h, w = model.config.resolution
    g = torch.Generator().manual_seed(1)
    rad = torch.rand(batch, 3, h, w, generator=g).pow(4) * 20
    dep = torch.rand(batch, 1, h, w, generator=g) * 4 + 1
    return rad.to(device), dep.to(device)


def train_step_fn(model, batch: int, device: str, amp: bool):
    """A closure running one full training step (the Trainer's arithmetic, without data loading)."""
    from roomlight.data import augment_batch
    from roomlight.losses import vae_loss

    opt = torch.optim.AdamW(model.parameters(), lr=2e-4, betas=(0.9, 0.99), weight_decay=0.01)
    rad, dep = fake_batch(model, batch, device)
    aug = torch.Generator().manual_seed(0)
    gen = torch.Generator(device=device).manual_seed(0)
    model.train()

    def step():
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

    return step


def current_rss() -> int:
    """Resident set size of this process now, in bytes (Linux /proc; else the peak so far)."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    import resource

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


def memory_child(preset: str, batch: int, threads: int) -> None:
    """Subprocess body: print peak RSS growth (bytes) of one training step as JSON."""
    import resource

    torch.set_num_threads(threads)
    model = make_model(preset, "cpu")
    step = train_step_fn(model, batch, "cpu", amp=False)
    before = current_rss()
    step()
    step()  # AdamW allocates its moments on the first step
    after = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    print(json.dumps({"before": before, "peak": after}))


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--train-repeats", type=int, default=3)
    ap.add_argument("--device", default="cuda" if torch.cuda.is_available() else "cpu")
    ap.add_argument("--decode-only", action="store_true", help="skip the training and memory rows")
    ap.add_argument("--memory-child", nargs=3, metavar=("PRESET", "BATCH", "THREADS"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.memory_child:
        memory_child(args.memory_child[0], int(args.memory_child[1]), int(args.memory_child[2]))
        return
    torch.set_num_threads(args.threads)
    dev = args.device
    cuda = dev == "cuda"
    sync = torch.cuda.synchronize if cuda else (lambda: None)
    rows = []

    model = make_model("default", dev).eval()
    params = sum(p.numel() for p in model.parameters())
    for b in (1, 32):
        z = torch.randn(b, model.config.latent_dim, device=dev)
        with torch.no_grad():
            t = median_time(lambda: model.decode(z), args.repeats if b == 1 else max(2, args.repeats // 2), sync=sync)
        rows.append((f"decode default 128x256, batch {b}", t * 1e3, "ms"))
        if b == 32:
            rows.append(("decode default 128x256, batch 32, per panorama", t * 1e3 / 32, "ms"))
    # Same run, same model: the literal upsampling (repeat + pad + 3x3 conv) the decoder used before
    # its phase decomposition, and bf16 autocast (fast where the CPU has AMX / AVX512-BF16).
    from roomlight.model.blocks import Upsample

    z = torch.randn(1, model.config.latent_dim, device=dev)
    fused = Upsample.forward
    Upsample.forward = Upsample.reference_forward
    try:
        with torch.no_grad():
            t_ref = median_time(lambda: model.decode(z), args.repeats, sync=sync)
            ref = model.decode_normalized(z).float()
    finally:
        Upsample.forward = fused
    with torch.no_grad():
        t_new = median_time(lambda: model.decode(z), args.repeats, sync=sync)
    rows.append(("decode default batch 1, literal upsampling (before)", t_ref * 1e3, "ms"))
    rows.append(("decode default batch 1, phase-decomposed upsampling", t_new * 1e3, "ms"))
    rows.append(("  speed-up, same run", t_ref / t_new, "x"))
    with torch.no_grad(), torch.autocast(dev, dtype=torch.bfloat16):
        t_bf = median_time(lambda: model.decode(z), args.repeats, sync=sync)
        err = (model.decode_normalized(z).float() - ref).pow(2).mean().sqrt().item()
    rows.append(("decode default batch 1, bf16 autocast", t_bf * 1e3, "ms"))
    rows.append(("  bf16 RMS error in normalised units (data std 1)", err, ""))
    if not cuda and args.threads != 1:
        # On a shared machine a second thread can cost more than it brings: show one thread too.
        torch.set_num_threads(1)
        z = torch.randn(1, model.config.latent_dim)
        with torch.no_grad():
            t = median_time(lambda: model.decode(z), args.repeats)
        rows.append(("decode default 128x256, batch 1, 1 thread", t * 1e3, "ms"))
        torch.set_num_threads(args.threads)

    for preset, batch in () if args.decode_only else (("default", 32), ("small", 32), ("tiny", 32)):
        m = make_model(preset, dev)
        step = train_step_fn(m, batch, dev, amp=cuda)
        reps = args.train_repeats if preset == "default" else args.repeats
        t = median_time(step, reps, warmup=1, sync=sync)
        h, w = m.config.resolution
        rows.append((f"train step {preset} {h}x{w}, batch {batch}", t * 1e3, "ms"))
        rows.append((f"training throughput {preset} {h}x{w}", batch / t, "panoramas/s"))
        del m, step

    if args.decode_only:
        pass
    elif cuda:
        m = make_model("default", dev)
        torch.cuda.reset_peak_memory_stats()
        step = train_step_fn(m, 32, dev, amp=True)
        step()
        step()
        sync()
        rows.append(("peak GPU memory, train step default batch 32", torch.cuda.max_memory_allocated() / 2**20, "MiB"))
    else:
        out = subprocess.run([sys.executable, __file__, "--memory-child", "default", "32", str(args.threads)],
                             capture_output=True, text=True, check=True)
        mem = json.loads(out.stdout.strip().splitlines()[-1])
        rows.append(("peak RSS, train step default batch 32 (process)", mem["peak"] / 2**20, "MiB"))
        rows.append(("peak RSS growth over the model alone", (mem["peak"] - mem["before"]) / 2**20, "MiB"))

    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    name = torch.cuda.get_device_name(0) if cuda else f"cpu, {args.threads} threads"
    print(f"device: {name}; torch {torch.__version__}; default model {params:,} parameters; "
          f"repeats {args.repeats} (train default: {args.train_repeats}), median; load average {load:.1f}")
    print("| benchmark | value | unit |\n|---|---:|---|")
    for n, v, u in rows:
        print(f"| {n} | {v:.2f} | {u} |")


if __name__ == "__main__":
    main()
