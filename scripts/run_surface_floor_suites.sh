#!/usr/bin/env bash
# The fitted prior with the visible room's floor on its own cells (`--set surface_floor=cell`) on both scored
# photo suites, paired per photo against the default fitted on the same photographs (and the prior at
# infinity), and against the committed paper-objective records (benchmarks/results/*-paper-objective, fitted
# on the first build of each suite: a rebuild from the seeds agrees to 0.002 dB on the oracle's probes, not
# to the bit). The suites must exist (scripts/run_photo_default_suites.sh builds them with the records'
# seeds). Resumable; ~25 min, ~50 with the defaults' fits.
set -euo pipefail
cd "$(dirname "$0")/.."
R=.venv/bin/roomlight
FIT=(--preset fast --eval-spp 64 --quiet)
$R bench run-photos bench/wide24 --out results/wide24-default "${FIT[@]}" --methods prior,prior-envmap
$R bench run-photos bench/photos24 --out results/photos24-room-bound "${FIT[@]}" --methods prior,prior-envmap
$R bench run-photos bench/wide24 --out results/wide24-cell-floor "${FIT[@]}" --methods prior --set surface_floor=cell
$R bench run-photos bench/photos24 --out results/photos24-cell-floor "${FIT[@]}" --methods prior --set surface_floor=cell
for pair in "wide24 wide24-default" "photos24 photos24-room-bound"; do
  set -- $pair
  echo "== $1: cell floor - default (and - prior-envmap)"
  .venv/bin/python scripts/compare_bench_runs.py results/$2 results/$1-cell-floor --suffix +cell --method prior
  echo "== $1: cell floor - paper objective (committed record)"
  .venv/bin/python scripts/compare_bench_runs.py benchmarks/results/$1-paper-objective results/$1-cell-floor \
      --suffix +cell --method prior
  .venv/bin/python scripts/photo_brightness.py results/$1-cell-floor --methods prior
done
