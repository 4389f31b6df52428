"""Candidate priors at an equal CPU budget: train each for the same minutes, score each the same way.

Each candidate is a model configuration and a start (the bundled prior's weights, grown to the
candidate's latent where it is larger, or random weights). The budget is converted to training
steps with each candidate's throughput, measured at the start on the quiet machine (training
panoramas/s, ``benchmarks/bench_prior_candidates.py``), so that other work on the machine later
cannot make one candidate's minutes shorter than another's. Then each candidate:

1. trains ``--minutes`` worth of steps of a long cosine schedule (``roomlight train ... --until-step``);
2. is scored by the trainer's validation pass (posterior-mean reconstructions of the validation rooms)
   and, when it starts from the bundled prior (``--eval-all``: every one), by the latent fit of the
   README protocol (encoder start, depth weighted 3x) on ``--eval-limit`` validation rooms
   (``roomlight eval-prior``).

Every stage is skipped when its output exists, so the script resumes where it stopped.

Run: .venv/bin/python scripts/compare_prior_candidates.py --data data/rooms64b --runs runs/cand
         [--minutes 8] [--candidates lite-continued,...] [--eval-limit 16] [--fit-steps 1500] [--no-eval]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
BUNDLED = ROOT / "src" / "roomlight" / "assets" / "prior"
sys.path.insert(0, str(ROOT / "benchmarks"))

#: name -> (model preset, ModelConfig overrides, start, peak learning rate). "bundled" starts from the
#: bundled prior (its latent grown where the candidate's is larger), "scratch" from random weights.
CANDIDATES = {
    "lite-continued": ("lite", {}, "bundled", 5e-4),
    "lite-l256-grown": ("lite", {"latent_dim": 256}, "bundled", 5e-4),
    "lite-l512-grown": ("lite", {"latent_dim": 512}, "bundled", 5e-4),
    "lite-scratch": ("lite", {}, "scratch", 1e-3),
    "lite-l512-scratch": ("lite", {"latent_dim": 512}, "scratch", 1e-3),
    "small-scratch": ("small", {}, "scratch", 1e-3),
}
#: The schedule every candidate is a prefix of (steps at batch 32): hours of training on this CPU.
SCHEDULE_STEPS = 12000
BATCH = 32


def roomlight(*args: str) -> None:
    cmd = [str(Path(sys.executable).with_name("roomlight")), *args]
    print("$ " + " ".join(cmd), flush=True)
    subprocess.run(cmd, check=True)


def measure_rates(names: list[str], path: Path) -> dict[str, float]:
    """Training panoramas/s of each candidate (cached in ``path``)."""
    from bench_prior_candidates import training_rate

    from roomlight.prior.model import Normalization, PanoVAE, get_preset
    import torch

    rates = json.loads(path.read_text()) if path.exists() else {}
    for name in names:
        preset, overrides, _, _ = CANDIDATES[name]
        arch = json.dumps([preset, overrides], sort_keys=True)  # one measurement per architecture
        if arch not in rates:
            torch.manual_seed(0)
            norm = Normalization(torch.tensor([0.95, 0.76, 0.61, 0.61]), torch.tensor([0.64, 0.60, 0.59, 0.52]))
            model = PanoVAE(get_preset(preset).override(**overrides), normalization=norm)
            rates[arch] = training_rate(model, repeats=8, batch=BATCH)
            print(f"{preset} {overrides}: {rates[arch]:.1f} training panoramas/s", flush=True)
            path.write_text(json.dumps(rates, indent=2) + "\n")
    return {name: rates[json.dumps([CANDIDATES[name][0], CANDIDATES[name][1]], sort_keys=True)] for name in names}


def train(name: str, run: Path, data: str, steps: int) -> None:
    preset, overrides, start, lr = CANDIDATES[name]
    done = run / "candidate-done.json"
    if done.exists():
        return
    args = ["train", "--data", data, "--out", str(run), "--config", preset, "--batch-size", str(BATCH),
            "--max-steps", str(SCHEDULE_STEPS), "--lr", str(lr), "--workers", "0", "--until-step", str(steps),
            "--set", "warmup_steps=100", "--set", "loss.peak=0.6", "--set", "val_every=100"]
    for k, v in overrides.items():
        args += ["--set", f"model_overrides.{k}={v}"]
    if start == "bundled":
        args += ["--init-from", str(BUNDLED), "--set", "loss.kl_warmup_steps=0"]
    roomlight(*args)  # resumes from the run's last checkpoint when re-run
    done.write_text(json.dumps({"until_step": steps}) + "\n")


def _events(run: Path, kind: str) -> list[dict]:
    log = run / "log.jsonl"
    if not log.exists():
        return []
    return [e for e in map(json.loads, log.read_text().splitlines()) if e.get("event") == kind]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", required=True, help="training rooms (a synth folder with train/ and val/)")
    ap.add_argument("--runs", required=True, help="folder for the candidates' runs")
    ap.add_argument("--minutes", type=float, default=8.0, help="CPU minutes of training per candidate")
    ap.add_argument("--candidates", default=",".join(CANDIDATES))
    ap.add_argument("--eval-limit", type=int, default=16, help="validation rooms in the latent-fit score")
    ap.add_argument("--fit-steps", type=int, default=1500)
    ap.add_argument("--no-eval", action="store_true", help="only train and read the trainer's validation")
    ap.add_argument("--eval-all", action="store_true",
                    help="also score the candidates trained from scratch by the latent fit (by default only those "
                         "that start from the bundled prior: after minutes from scratch a network is far from "
                         "competing, which the trainer's validation already shows)")
    args = ap.parse_args()
    names = [n.strip() for n in args.candidates.split(",") if n.strip()]
    bad = [n for n in names if n not in CANDIDATES]
    if bad:
        ap.error(f"unknown candidates {bad}; choose from {', '.join(CANDIDATES)}")
    runs = Path(args.runs)
    runs.mkdir(parents=True, exist_ok=True)
    rates = measure_rates(names, runs / "rates.json")
    rows = []
    for name in names:
        steps = int(rates[name] * args.minutes * 60 / BATCH)
        run = runs / name
        train(name, run, args.data, steps)
        val = _events(run, "val")
        last = val[-1] if val else {}
        fit = {}
        if not args.no_eval and (args.eval_all or CANDIDATES[name][2] == "bundled"):
            out = run / f"eval-val{args.eval_limit}"
            if not (out / "eval_prior.json").exists():
                roomlight("eval-prior", "--model", str(run), "--data", args.data, "--split", "val", "--limit",
                          str(args.eval_limit), "--fit-steps", str(args.fit_steps), "--batch-size", "16",
                          "--fit-init", "encoder", "--depth-weight", "3", "--out", str(out))
            fit = json.loads((out / "eval_prior.json").read_text())["rows"]["latent fit"]
        preset, overrides, start, lr = CANDIDATES[name]
        rows.append((name, start, f"{rates[name]:.1f}", steps, last, fit))
    print(f"\n| candidate | start | training panoramas/s | steps in {args.minutes:g} min | val PSNR LDR ↑ "
          "| val peak loss ↓ | val AbsRel ↓ | fit PSNR LDR ↑ | fit peak error (stops) ↓ | fit AbsRel ↓ |")
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for name, start, rate, steps, v, f in rows:
        def g(d, k, fmt):
            return format(d[k], fmt) if k in d and d[k] is not None else "–"
        print(f"| {name} | {start} | {rate} | {steps} | {g(v, 'psnr_ldr', '.2f')} | {g(v, 'peak', '.3f')} "
              f"| {g(v, 'abs_rel', '.4f')} | {g(f, 'psnr_ldr', '.2f')} | {g(f, 'peak_stops', '.2f')} "
              f"| {g(f, 'abs_rel', '.4f')} |")


if __name__ == "__main__":
    main()
