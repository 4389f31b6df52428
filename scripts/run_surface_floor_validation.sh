#!/usr/bin/env bash
# The containment floor under the visible room, own cell only (`--set surface_floor=cell`) against the default
# (every point enclosed, its need spread over the 3 x 3 cells around it), on validation photos only:
# bench/wide-val-clean and bench/photos-val8-hr (scripts/run_hires_validation.sh builds them) and
# bench/wide-val-realmetal (scripts/run_real_metal_validation.sh). The defaults are those sets' committed-code
# runs (results/*-mb-default, results/wide-val-realmetal-default); `fast` preset, probes at 64 spp,
# photos-val8-hr at its full 192 x 256 px as its earlier runs. Then both sides again with the fit's seed 1000
# (results/*-seed1000 hold the defaults' for the first two sets), and each side averaged over its two seeds
# before pairing: one seed's paired verdict can be the seed's. Resumable; ~40 min.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/validation_photos.sh   # R, run_validation
hr=(--set render_size=256 --set geometry_size=512)
run_validation wide-val-clean cell-floor --set surface_floor=cell
run_validation photos-val8-hr cell-floor "${hr[@]}" --set surface_floor=cell
run_validation wide-val-realmetal cell-floor --set surface_floor=cell
run_validation wide-val-clean cell-floor-seed1000 --set surface_floor=cell --set seed=1000
run_validation photos-val8-hr cell-floor-seed1000 "${hr[@]}" --set surface_floor=cell --set seed=1000
run_validation wide-val-realmetal seed1000 --set seed=1000
run_validation wide-val-realmetal cell-floor-seed1000 --set surface_floor=cell --set seed=1000
for pair in "wide-val-clean mb-default lr-seed1000" "photos-val8-hr mb-default seed1000" \
            "wide-val-realmetal default seed1000"; do
  set -- $pair
  echo "== $1: cell floor - default (seed 0)"
  .venv/bin/python scripts/compare_bench_runs.py results/$1-$2 results/$1-cell-floor --suffix +cell --method prior
  .venv/bin/python scripts/photo_brightness.py results/$1-cell-floor --against results/$1-$2 --methods prior
  echo "== $1: cell floor - default, each averaged over seeds 0 and 1000"
  .venv/bin/python scripts/compare_bench_runs.py results/$1-$2,results/$1-$3 \
      results/$1-cell-floor,results/$1-cell-floor-seed1000 --suffix +cell --method prior
done
