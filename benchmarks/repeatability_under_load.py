"""Does the same photo fit give the same numbers on an idle machine and beside another CPU-heavy job?

Fits a photo case (``roomlight fit-photo``, fast preset, a short run; the built-in example case
unless ``--case``) ``--repeats`` times on the idle machine and ``--repeats`` times while ``--busy``
other processes spin on the CPU (a pure-Python loop each, like any other job), once per thread policy:

- ``default``: the CPUs this process may use, whatever else runs (:mod:`roomlight.cli.threads`);
- ``--threads auto``: the CPUs other processes leave free, measured when the command starts: fewer
  threads beside the busy processes, and torch splits its float reductions by thread.

Each run's history (every number but the wall times) is compared with the first idle run of the same
setting; the table gives how many runs match it bit for bit, the largest difference of the final
objective and the fit's median wall time.

Run: .venv/bin/python benchmarks/repeatability_under_load.py [--repeats 2] [--busy 1] [--iterations 30]
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src"


def _spin() -> None:  # pragma: no cover - a busy process, killed by the parent
    while True:
        pass


def _fit(case: Path, out: Path, iterations: int, flags: list[str]) -> tuple[list, float]:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(SRC), os.environ.get("PYTHONPATH", "")])}
    for name in ("ROOMLIGHT_THREADS", "ROOMLIGHT_THREADS_AUTO", "ROOMLIGHT_DETERMINISTIC", "OMP_NUM_THREADS",
                 "OMP_WAIT_POLICY", "KMP_BLOCKTIME"):
        env.pop(name, None)
    cmd = [sys.executable, "-m", "roomlight.cli.main", *flags, "fit-photo", str(case), "--out", str(out),
           "--preset", "fast", "--iterations", str(iterations), "--quiet", "--restart",
           "--set", "probe_count=0", "--set", "eval_every=10"]
    t0 = time.perf_counter()
    r = subprocess.run(cmd, env=env, capture_output=True, text=True)
    seconds = time.perf_counter() - t0
    if r.returncode != 0:
        raise SystemExit(f"fit failed:\n{r.stderr[-3000:]}")
    rows = [json.loads(line) for line in (out / "history.jsonl").read_text().splitlines()]
    numbers = [{k: v for k, v in row.items() if "second" not in k and k != "time"} for row in rows]
    return numbers, seconds


def _final_objective(numbers: list) -> float:
    for row in reversed(numbers):
        for key in ("objective", "loss", "total"):
            if key in row and isinstance(row[key], (int, float)):
                return float(row[key])
    return float("nan")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=2, help="fits per machine state and setting")
    ap.add_argument("--busy", type=int, default=1, help="spinning processes beside the loaded fits")
    ap.add_argument("--iterations", type=int, default=30)
    ap.add_argument("--case", type=Path, help="a photo case folder [default: the built-in example case]")
    ap.add_argument("--json", type=Path, help="write every run's numbers here")
    args = ap.parse_args(argv)

    from roomlight.fitting.photo.synthetic import example_photo_case

    rows, record = [], {}
    with tempfile.TemporaryDirectory() as tmp:
        case = args.case
        if case is None:
            case = Path(tmp) / "case"
            example_photo_case(case)
        for setting, flags in (("default", []), ("--threads auto", ["--threads", "auto"])):
            runs = []
            for state in ("idle", "loaded"):
                spinners = []
                if state == "loaded":
                    spinners = [multiprocessing.Process(target=_spin, daemon=True) for _ in range(args.busy)]
                    for p in spinners:
                        p.start()
                    time.sleep(1.0)
                try:
                    for i in range(args.repeats):
                        numbers, seconds = _fit(case, Path(tmp) / f"fit-{len(flags)}-{state}-{i}", args.iterations,
                                                flags)
                        runs.append((state, numbers, seconds))
                        print(f"  {setting}, {state} #{i + 1}: {seconds:.1f} s, final objective "
                              f"{_final_objective(numbers):.9g}", flush=True)
                finally:
                    for p in spinners:
                        p.kill()
            reference = runs[0][1]
            for state in ("idle", "loaded"):
                mine = [r for r in runs if r[0] == state]
                same = sum(r[1] == reference for r in mine)
                spread = max(abs(_final_objective(r[1]) - _final_objective(reference)) for r in mine)
                rows.append((setting, state, f"{same}/{len(mine)}", spread, statistics.median(r[2] for r in mine)))
            record[setting] = [{"state": s, "seconds": t, "history": n} for s, n, t in runs]

    print()
    print("| threads | machine | histories equal to the first idle fit | largest |Δ final objective| | "
          "fit + start-up, median (s) |")
    print("|---|---|:---:|---:|---:|")
    for setting, state, same, spread, seconds in rows:
        print(f"| {setting} | {state} | {same} | {spread:.3g} | {seconds:.1f} |")
    if args.json:
        args.json.write_text(json.dumps(record))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
