#!/usr/bin/env bash
# The inserted objects' headline comparison against a clean truth (docs/results.md, "Inserted objects: the
# 2.5D light against infinity", composites at 1024 spp) made again so that benchmarks/insertion_diagnosis.py
# prints it paired per photo as well as per object: the original suite built, its prior and prior-envmap
# fitted, every object composited at 1024 spp and scored against the room traced again at 4096 spp.
# One heavy job at a time, on an idle machine; resumable (each step keeps what it finished).
set -euo pipefail
cd "$(dirname "$0")/.."
R=.venv/bin/roomlight
$R bench make-photos --out bench/photos24 --n 24 --seed 400100 --res 96x128 --spp 64 --probe-spp 256 --quiet
$R bench run-photos bench/photos24 --out results/photos24-room-bound --preset fast --eval-spp 64 --quiet \
    --methods prior,prior-envmap
echo "== the fits again - the committed records (zero everywhere where today's code reproduces them)"
.venv/bin/python scripts/compare_bench_runs.py benchmarks/results/photos24-room-bound results/photos24-room-bound \
    --suffix +now --method prior
.venv/bin/python benchmarks/insertion_diagnosis.py bench/photos24 --results results/photos24-room-bound --quick \
    --spp 1024 --truth-spp 4096 --out results/insertion-clean.json > results/insertion-clean.md
cat results/insertion-clean.md
