"""The command line's thread policy against torch's defaults, as found and next to a busy process.

The workload is the core of ``roomlight fit-pano``: a latent fit of the bundled prior to the
built-in example room (``--steps`` Adam steps of decoder forward + backward), in a fresh process
per measurement so that OpenMP's settings take effect:

- ``before``: torch's defaults (as many threads as the machine has, OpenMP's spinning wait);
- ``default``: roomlight's default (:mod:`roomlight.cli.threads`): the CPUs this process may use,
  OpenMP threads that sleep when idle if other processes keep a CPU busy when it starts;
- ``auto``: ``--threads auto``: the same waiting, and the CPUs less the busy ones.

"Under load" runs the same while ``--busy`` other processes spin on the CPU (a pure-Python loop
each, like any other job). Times are the median of ``--repeats`` runs, in seconds for the fit
alone (process start and model loading excluded).

"Load arriving later" runs ``--phases`` fits in one process that chose its threads on an idle
machine; the busy processes start after the first phase. ``default`` keeps its count and its waiting;
``auto`` measures the load again before each phase (:func:`roomlight.core.render.variant.recheck_threads`,
as the long commands do between their cases and validations). Its times are the median over the
phases after the load arrived.

Run: .venv/bin/python benchmarks/bench_threads.py [--steps 100] [--repeats 3] [--busy 1] [--phases 5]
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

#: The workload's set-up, shared by both child scripts: the bundled prior, the example room, a warm-up fit.
LOAD_AND_WARM_UP = r"""
import torch
from roomlight.demo import bundled_prior_path
from roomlight.core.examples import example_room
from roomlight.prior.latent_fit import LatentFitConfig, fit_latent
from roomlight.prior.model import PanoVAE

model = PanoVAE.from_pretrained(bundled_prior_path())
h, w = model.config.resolution
rad, dep = example_room(h)
rad = rad.permute(2, 0, 1)[None].float()
dep = dep[None, None].float()
fit_latent(model, rad, dep, LatentFitConfig(steps=2))  # warm-up
"""

CHILD = r"""
import json, os, sys, time
if os.environ.get("BENCH_POLICY") in ("default", "auto"):
    from roomlight.cli.threads import apply_thread_policy, default_threads, prepare_environment
    prepare_environment()
    if os.environ["BENCH_POLICY"] == "auto":
        os.environ["ROOMLIGHT_THREADS"] = "auto"
    default_threads()
    apply_thread_policy()
""" + LOAD_AND_WARM_UP + r"""
t = time.perf_counter()
fit_latent(model, rad, dep, LatentFitConfig(steps=int(sys.argv[1])))
print(json.dumps({"seconds": time.perf_counter() - t, "threads": torch.get_num_threads(),
                  "wait": os.environ.get("OMP_WAIT_POLICY", "default")}))
"""

PHASES_CHILD = r"""
import json, os, sys, time
from roomlight.cli.threads import apply_thread_policy, default_threads, prepare_environment
prepare_environment()
if os.environ.get("BENCH_POLICY") == "auto":
    os.environ["ROOMLIGHT_THREADS"] = "auto"
default_threads()
apply_thread_policy()
""" + LOAD_AND_WARM_UP + r"""
from roomlight.core.render.variant import recheck_threads
for phase in range(int(sys.argv[2])):
    if phase:
        time.sleep(0.5)  # the parent starts the busy processes after the first phase
    recheck_threads()  # does nothing unless the policy is 'auto'
    t = time.perf_counter()
    fit_latent(model, rad, dep, LatentFitConfig(steps=int(sys.argv[1])))
    print(json.dumps({"phase": phase, "seconds": time.perf_counter() - t, "threads": torch.get_num_threads()}),
          flush=True)
"""


def run_phases(policy: str, steps: int, phases: int, busy: int) -> dict:
    """One process of ``phases`` fits; ``busy`` spinning processes start once the first is done."""
    env = {k: v for k, v in os.environ.items()
           if k not in ("OMP_WAIT_POLICY", "OMP_NUM_THREADS", "KMP_BLOCKTIME", "ROOMLIGHT_THREADS",
                        "ROOMLIGHT_THREADS_AUTO")}
    env["BENCH_POLICY"] = policy
    src = Path(__file__).resolve().parents[1] / "src"
    env["PYTHONPATH"] = os.pathsep.join([str(src), env.get("PYTHONPATH", "")])
    proc = subprocess.Popen([sys.executable, "-c", PHASES_CHILD, str(steps), str(phases)], env=env,
                            stdout=subprocess.PIPE, text=True)
    stop = multiprocessing.Event()
    spinners, rows = [], []
    try:
        for line in proc.stdout:
            rows.append(json.loads(line))
            if len(rows) == 1:
                spinners = [multiprocessing.Process(target=_spin, args=(stop,), daemon=True) for _ in range(busy)]
                for p in spinners:
                    p.start()
        proc.wait()
    finally:
        stop.set()
        for p in spinners:
            p.join()
    later = rows[1:]
    return {"first": rows[0]["seconds"], "seconds": statistics.median(r["seconds"] for r in later),
            "threads": f"{rows[0]['threads']} -> {later[-1]['threads']}"}


def _spin(stop) -> None:
    x = 0
    while not stop.is_set():
        x = (x * 1103515245 + 12345) % 2147483648


def run_once(policy: str, steps: int) -> dict:
    env = {k: v for k, v in os.environ.items()
           if k not in ("OMP_WAIT_POLICY", "OMP_NUM_THREADS", "KMP_BLOCKTIME", "ROOMLIGHT_THREADS",
                        "ROOMLIGHT_THREADS_AUTO")}
    env["BENCH_POLICY"] = policy
    src = Path(__file__).resolve().parents[1] / "src"
    env["PYTHONPATH"] = os.pathsep.join([str(src), env.get("PYTHONPATH", "")])
    out = subprocess.run([sys.executable, "-c", CHILD, str(steps)], env=env, capture_output=True, text=True,
                         check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def measure(policy: str, steps: int, repeats: int) -> dict:
    runs = [run_once(policy, steps) for _ in range(repeats)]
    return {"seconds": statistics.median(r["seconds"] for r in runs), "threads": runs[-1]["threads"],
            "wait": runs[-1]["wait"]}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=100, help="latent-fit steps per measurement")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--busy", type=int, default=1, help="busy processes for the 'under load' row")
    ap.add_argument("--phases", type=int, default=5, help="fits per process in the 'load arriving later' rows")
    args = ap.parse_args()
    load_before = os.getloadavg()[0]

    rows = []
    for load in ("as found", "under load"):
        stop = multiprocessing.Event()
        spinners = []
        if load == "under load":
            spinners = [multiprocessing.Process(target=_spin, args=(stop,), daemon=True) for _ in range(args.busy)]
            for p in spinners:
                p.start()
            time.sleep(0.5)
        try:
            before = measure("before", args.steps, args.repeats)
            default = measure("default", args.steps, args.repeats)
            auto = measure("auto", args.steps, args.repeats)
        finally:
            stop.set()
            for p in spinners:
                p.join()
        rows.append((load, before, default, auto))

    print(f"Latent fit of the bundled prior, {args.steps} steps; median of {args.repeats}; "
          f"{os.cpu_count()} CPUs, load average before the run {load_before:.2f}\n")
    print("| machine | torch defaults | roomlight's default | `--threads auto` | default's speed-up | auto's |")
    print("|---|---:|---:|---:|---:|---:|")
    for load, *cols in rows:
        label = load if load == "as found" else f"{load} (+{args.busy} busy process{'es' if args.busy > 1 else ''})"
        cells = " | ".join(f"{c['seconds']:.2f} s ({c['threads']} thr., {c['wait'].lower()})" for c in cols)
        print(f"| {label} | {cells} | {cols[0]['seconds'] / cols[1]['seconds']:.1f}× | "
              f"{cols[0]['seconds'] / cols[2]['seconds']:.1f}× |")

    late = {policy: [run_phases(policy, args.steps, args.phases, args.busy) for _ in range(args.repeats)]
            for policy in ("default", "auto")}
    print(f"\nLoad arriving later: {args.phases} fits of {args.steps} steps in one process, +{args.busy} busy "
          f"process(es) from the second on; medians of {args.repeats} processes\n")
    print("| threads chosen | first fit (idle) | fits after the load arrived | threads |")
    print("|---|---:|---:|---|")
    for policy, label in (("default", "default: fixed at the start"), ("auto", "auto: re-checked before each fit")):
        runs = late[policy]
        first = statistics.median(r["first"] for r in runs)
        later = statistics.median(r["seconds"] for r in runs)
        print(f"| {label} | {first:.2f} s | {later:.2f} s | {runs[-1]['threads']} |")
    ratio = statistics.median(r["seconds"] for r in late["default"]) / statistics.median(
        r["seconds"] for r in late["auto"])
    print(f"\nauto's re-checking: {ratio:.1f}x faster once the load arrived")


if __name__ == "__main__":
    main()
