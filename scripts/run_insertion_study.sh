#!/usr/bin/env bash
# Inserted objects placed independently of the probes (docs/results.md, "Inserted objects: the 2.5D light
# against infinity"): the original suite's 24 photos rebuilt with 4 objects each, one per stratum (near,
# middle, far, raised), then every light composited and scored by benchmarks/insertion_diagnosis.py. The
# photos are the same as bench/photos24's (same seeds), so the fits of results/photos24-room-bound apply.
# Run by scripts/run_photo_default_suites.sh once the fits it uses are made; resumable.
set -euo pipefail
cd "$(dirname "$0")/.."

.venv/bin/roomlight bench make-photos --out bench/photos24s --n 24 --seed 400100 --res 96x128 --spp 64 --probe-spp 256 \
    --inserts 4 --inserts-at stratified --quiet
.venv/bin/python benchmarks/insertion_diagnosis.py bench/photos24s --results results/photos24-room-bound --quick \
    --out results/insertion-stratified.json > results/insertion-stratified.md
