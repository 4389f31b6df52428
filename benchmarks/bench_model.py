"""Speed and memory of the prior: decode latency, training throughput, peak training memory.

- decode latency of the paper's model at 128 x 256, batch 1 and 32 (target batch 1 <= 120 ms
  with 2 CPU threads);
- training throughput (panoramas / s) of full training steps (forward, the paper's loss,
  backward, AdamW) at batch 32, for every preset (``--presets``), and with ``--compare PRESET``
  that preset before/after the padding adjoint, channels-last (and compiled with
  ``--with-compile``), timed alternately in one run;
- peak memory of a training step at batch 32 (CPU: the process's peak resident set size, in a
  fresh subprocess, minus its size before the step; CUDA: torch.cuda.max_memory_allocated).

Prints a Markdown table of medians (first runs excluded as warm-up).
Run: .venv/bin/python benchmarks/bench_model.py [--threads 2] [--repeats 5] [--device cpu|cuda] [--decode-only]
     [--presets default,small,compact,lite,tiny] [--compare lite]
"""

from __future__ import annotations

import argparse
import contextlib
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


@contextlib.contextmanager
def literal_blocks():
    """Temporarily run the decoder's blocks by their literal definitions (the pre-fusion code):
    nearest upsampling materialised, SiLU as its own pass before padding, AdaGN as GroupNorm
    followed by a separate scale and shift."""
    import torch.nn.functional as F

    from roomlight.core.geometry.padding import spherical_pad
    from roomlight.prior.model import blocks

    def literal_adagn(self, x, z):
        scale, shift = self.to_scale_shift(z).chunk(2, dim=1)
        h = F.group_norm(x, self.groups, eps=self.eps)
        return h * (1.0 + scale[:, :, None, None]) + shift[:, :, None, None]

    def literal_pad(x, pad=1, silu=False):
        return spherical_pad(F.silu(x) if silu else x, pad)

    saved = (blocks.Upsample.forward, blocks.AdaGN.forward, blocks.spherical_pad)
    blocks.Upsample.forward = blocks.Upsample.reference_forward
    blocks.AdaGN.forward = literal_adagn
    blocks.spherical_pad = literal_pad
    try:
        yield
    finally:
        blocks.Upsample.forward, blocks.AdaGN.forward, blocks.spherical_pad = saved


def paired_median_times(fn, context, repeats: int, sync=lambda: None) -> tuple[float, float]:
    """Medians of fn() inside ``context()`` and outside it, timed alternately call by call so
    that slow phases of a shared machine hit both equally. Returns (inside, outside) seconds."""
    inside, outside = [], []
    for k in range(repeats + 1):
        for times, ctx in ((inside, context), (outside, contextlib.nullcontext)):
            with ctx():
                t0 = time.perf_counter()
                fn()
                sync()
                if k:  # the first round is warm-up
                    times.append(time.perf_counter() - t0)
    return statistics.median(inside), statistics.median(outside)


def cpu_has_native_bf16() -> bool:
    """True when /proc/cpuinfo lists AMX-BF16 or AVX512-BF16 (unknown platforms: False)."""
    try:
        flags = open("/proc/cpuinfo").read()
    except OSError:
        return False
    return "amx_bf16" in flags or "avx512_bf16" in flags


def make_model(preset: str, device: str):
    from roomlight.prior.model import Normalization, PanoVAE, get_preset

    torch.manual_seed(0)
    norm = Normalization(mean=(0.9, 0.8, 0.5, 1.0), std=(0.6, 0.6, 0.55, 0.45))
    return PanoVAE(get_preset(preset), norm).to(device)


def fake_batch(model, batch: int, device: str):
    h, w = model.config.resolution
    g = torch.Generator().manual_seed(1)
    rad = torch.rand(batch, 3, h, w, generator=g).pow(4) * 20
    dep = torch.rand(batch, 1, h, w, generator=g) * 4 + 1
    return rad.to(device), dep.to(device)


def train_step_fn(model, batch: int, device: str, amp: bool, channels_last: bool = False):
    """A closure running one full training step (the Trainer's arithmetic, without data loading)."""
    from roomlight.prior.data import augment_batch
    from roomlight.prior.losses import vae_loss

    opt = torch.optim.AdamW(model.parameters(), lr=2e-4, betas=(0.9, 0.99), weight_decay=0.01)
    rad, dep = fake_batch(model, batch, device)
    if channels_last:
        rad, dep = rad.contiguous(memory_format=torch.channels_last), dep.contiguous(memory_format=torch.channels_last)
    aug = torch.Generator().manual_seed(0)
    gen = torch.Generator(device=device).manual_seed(0)
    model.train()

    # The phases are labelled for torch.profiler (benchmarks/profile_train_step.py); outside a
    # profiler a label costs microseconds against a step of tens of milliseconds or more.
    phase = torch.profiler.record_function

    def step():
        with phase("phase: augmentation"):
            r, d = augment_batch(rad, dep, aug)
            x = model.normalization.normalize(r, d)
        with phase("phase: forward"), torch.autocast(device_type=device, dtype=torch.bfloat16, enabled=amp):
            x_hat, post = model(x, True, gen)
        with phase("phase: loss"):
            loss = vae_loss(x_hat.float(), x, post.mean.float(), post.logvar.float(), 500, model.normalization,
                            target_radiance=r)["total"]
        with phase("phase: backward"):
            opt.zero_grad(set_to_none=True)
            loss.backward()
        with phase("phase: optimiser"):
            torch.nn.utils.clip_grad_norm_(model.parameters(), 10.0)
            opt.step()

    return step


@contextlib.contextmanager
def autograd_padding():
    """Temporarily differentiate spherical padding by autograd through its slice copies (the
    code before the hand-written adjoint)."""
    from roomlight.core.geometry import padding

    saved = padding._SphericalPadFunction.apply
    padding._SphericalPadFunction.apply = lambda x, pad: padding._pad_forward(x, pad)
    try:
        yield
    finally:
        padding._SphericalPadFunction.apply = saved


def compare_training_variants(preset: str, dev: str, repeats: int, sync, with_compile: bool) -> list[tuple]:
    """Training-step time of one preset: spherical padding differentiated by autograd (before),
    with its hand-written adjoint (now), then channels-last tensors and, with ``with_compile``,
    ``torch.compile`` of the encoder and decoder (the Trainer's ``compile`` option). Same maths;
    timed round-robin call by call in one run so a busy machine slows all alike. Compilation
    happens in a warm-up call and is reported separately."""
    names = ["autograd padding (before)", "hand-written padding adjoint", "channels-last"]
    names += ["torch.compile"] if with_compile else []
    steps, contexts = {}, {}
    for name in names:
        torch.manual_seed(0)
        m = make_model(preset, dev)
        if name == "channels-last":
            m = m.to(memory_format=torch.channels_last)
        if name == "torch.compile":
            m.encoder.compile()
            m.decoder.compile()
        steps[name] = train_step_fn(m, 32, dev, amp=dev == "cuda", channels_last=name == "channels-last")
        contexts[name] = autograd_padding if name.endswith("(before)") else contextlib.nullcontext
    compile_s = None
    if with_compile:
        t0 = time.perf_counter()
        steps["torch.compile"]()
        compile_s = time.perf_counter() - t0
    times = {k: [] for k in names}
    for k in range(repeats + 1):
        for name in names:
            with contexts[name]():
                t0 = time.perf_counter()
                steps[name]()
                sync()
            if k:
                times[name].append(time.perf_counter() - t0)
    med = {k: statistics.median(v) for k, v in times.items()}
    h, w = make_model(preset, "cpu").config.resolution
    base = med[names[0]]
    rows = []
    for name in names:
        rows.append((f"{preset} {h}x{w} train step, {name}", med[name] * 1e3, "ms"))
        rows.append((f"  {preset} throughput, {name}", 32 / med[name], "panoramas/s"))
        if name != names[0]:
            rows.append(("  speed-up over the first row, same run", base / med[name], "x"))
    if compile_s is not None:
        rows.append((f"{preset} torch.compile time (first step)", compile_s, "s"))
    return rows


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


def decode_rows(model, args, dev: str, cuda: bool, sync) -> list[tuple]:
    """Decode latency of the default model: batch 1 and 32, the literal blocks against the fused
    ones (alternating call by call), bf16 autocast where the hardware has it, one thread."""
    rows = []
    for b in (1, 32):
        z = torch.randn(b, model.config.latent_dim, device=dev)
        with torch.no_grad():
            t = median_time(lambda: model.decode(z), args.repeats if b == 1 else max(2, args.repeats // 2), sync=sync)
        rows.append((f"decode default 128x256, batch {b}", t * 1e3, "ms"))
        if b == 32:
            rows.append(("decode default 128x256, batch 32, per panorama", t * 1e3 / 32, "ms"))
    # Same run, same model, alternating call by call: the literal decoder (upsample by repeat +
    # pad + 3x3 conv, SiLU then pad, GroupNorm then affine) against the one in the package.
    z = torch.randn(1, model.config.latent_dim, device=dev)
    with torch.no_grad():
        with literal_blocks():
            ref = model.decode_normalized(z).float()
        t_ref, t_new = paired_median_times(lambda: model.decode(z), literal_blocks, args.repeats, sync)
        max_diff = (model.decode_normalized(z).float() - ref).abs().max().item()
    rows.append(("decode default batch 1, literal blocks (before)", t_ref * 1e3, "ms"))
    rows.append(("decode default batch 1, fused blocks", t_new * 1e3, "ms"))
    rows.append(("  speed-up, same run", t_ref / t_new, "x"))
    rows.append(("  max |difference| in normalised units", max_diff, ""))
    if cuda or cpu_has_native_bf16():
        with torch.no_grad(), torch.autocast(dev, dtype=torch.bfloat16):
            t_bf = median_time(lambda: model.decode(z), args.repeats, sync=sync)
            err = (model.decode_normalized(z).float() - ref).pow(2).mean().sqrt().item()
        rows.append(("decode default batch 1, bf16 autocast", t_bf * 1e3, "ms"))
        rows.append(("  bf16 RMS error in normalised units (data std 1)", err, ""))
    else:  # emulated bf16 is two orders of magnitude slower (23 s for one decode on an AVX2 EPYC)
        rows.append(("decode default batch 1, bf16 autocast: skipped, no AMX / AVX512-BF16", float("nan"), ""))
    if not cuda and args.threads != 1:
        # On a shared machine a second thread can cost more than it brings: show one thread too.
        torch.set_num_threads(1)
        z = torch.randn(1, model.config.latent_dim)
        with torch.no_grad():
            t = median_time(lambda: model.decode(z), args.repeats)
        rows.append(("decode default 128x256, batch 1, 1 thread", t * 1e3, "ms"))
        torch.set_num_threads(args.threads)
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--train-repeats", type=int, default=3)
    ap.add_argument("--device", default="cuda" if torch.cuda.is_available() else "cpu")
    ap.add_argument("--decode-only", action="store_true", help="skip the training and memory rows")
    ap.add_argument("--train-only", action="store_true", help="skip the decode rows")
    ap.add_argument("--presets", default="default,small,compact,lite,tiny",
                    help="comma-separated presets whose training throughput is measured")
    ap.add_argument("--compare", default="", metavar="PRESET",
                    help="also time this preset's training step with padding differentiated by autograd "
                         "(before), with its adjoint, and channels-last, alternating call by call in one run")
    ap.add_argument("--with-compile", action="store_true",
                    help="add torch.compile to --compare (minutes of compilation on a CPU)")
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
    if not args.train_only:
        rows += decode_rows(model, args, dev, cuda, sync)

    presets = tuple(p for p in args.presets.split(",") if p)
    for preset in () if args.decode_only else presets:
        batch = 32
        m = make_model(preset, dev)
        step = train_step_fn(m, batch, dev, amp=cuda)
        reps = args.train_repeats if preset == "default" else args.repeats
        t = median_time(step, reps, warmup=1, sync=sync)
        h, w = m.config.resolution
        rows.append((f"train step {preset} {h}x{w}, batch {batch}", t * 1e3, "ms"))
        rows.append((f"training throughput {preset} {h}x{w}", batch / t, "panoramas/s"))
        del m, step
    if args.compare and not args.decode_only:
        rows += compare_training_variants(args.compare, dev, args.repeats, sync, args.with_compile)

    if args.decode_only or "default" not in presets:
        pass  # the memory rows are about the default model's training step
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
