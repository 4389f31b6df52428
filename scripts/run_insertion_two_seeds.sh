#!/usr/bin/env bash
# The fitted prior's lead over itself at infinity on inserted objects, judged against the fit's seed:
# the original suite's prior and prior-envmap fitted again with another seed (`--set seed=1000`), then the
# insertion study's headline run (composites at 1024 spp, clean truth at 4096 spp) over both seeds' lights
# in one pass (the references rendered once); its tables add each method averaged over the two seeds
# ("prior (mean of 2 runs)"). ~12 min of fits, then ~3 min a photo (24 photos); resumable.
# Needs bench/photos24 and results/photos24-room-bound (scripts/run_insertion_by_photo.sh builds both).
set -euo pipefail
cd "$(dirname "$0")/.."
R=.venv/bin/roomlight
$R bench run-photos bench/photos24 --out results/photos24-seed1000 --preset fast --eval-spp 64 --quiet \
    --methods prior,prior-envmap --set seed=1000
.venv/bin/python benchmarks/insertion_diagnosis.py bench/photos24 --results results/photos24-room-bound \
    --results results/photos24-seed1000 --quick --spp 1024 --truth-spp 4096 --out results/insertion-clean-2seeds.json
