#!/usr/bin/env bash
# The fitted prior with the visible room's floor on its own cells (`--set surface_floor=cell`) on both scored
# photo suites, against the committed default and paper-objective records (benchmarks/results/wide24-room-bound,
# wide24-paper-objective, photos24-room-bound, photos24-paper-objective) and the prior at infinity, paired per
# photo. The suites must exist (scripts/run_photo_default_suites.sh builds them with the records' seeds).
# Resumable; ~30 min.
set -euo pipefail
cd "$(dirname "$0")/.."
R=.venv/bin/roomlight
FIT=(--preset fast --eval-spp 64 --quiet)
$R bench run-photos bench/wide24 --out results/wide24-cell-floor "${FIT[@]}" --methods prior --set surface_floor=cell
$R bench run-photos bench/photos24 --out results/photos24-cell-floor "${FIT[@]}" --methods prior --set surface_floor=cell
for suite in wide24 photos24; do
  for base in room-bound paper-objective; do
    echo "== $suite: cell floor - $base"
    .venv/bin/python scripts/compare_bench_runs.py benchmarks/results/$suite-$base results/$suite-cell-floor \
        --suffix +cell --method prior
  done
  .venv/bin/python scripts/photo_brightness.py results/$suite-cell-floor --methods prior
done
