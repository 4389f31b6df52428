#!/usr/bin/env bash
# The real-metal bound (`--set metal_band=1`: no fitted metal's mean albedo between a clear coat's 0.06 and
# the darkest pure metal's 0.45) against the defaults, on validation photos only: the wide suite's with real
# metals (bench/wide-val-realmetal, scripts/run_real_metal_validation.sh builds it), and the validation
# scenes of both suites whose metals are drawn like any albedo (bench/wide-val-clean, bench/photos-val8-hr,
# scripts/run_hires_validation.sh builds them). Both sides fitted now, one after the other (`fast` preset,
# probes at 64 spp; photos-val8-hr at its full 192 x 256 px as its earlier runs). Resumable; ~30 min.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/validation_photos.sh   # R, run_validation, build_real_metal_photos
build_real_metal_photos
hr=(--set render_size=256 --set geometry_size=512)
run_validation wide-val-realmetal default
run_validation wide-val-realmetal metal-band --set metal_band=1
run_validation wide-val-clean mb-default
run_validation wide-val-clean mb-metal-band --set metal_band=1
run_validation photos-val8-hr mb-default "${hr[@]}"
run_validation photos-val8-hr mb-metal-band "${hr[@]}" --set metal_band=1
for pair in "wide-val-realmetal default metal-band" "wide-val-clean mb-default mb-metal-band" \
            "photos-val8-hr mb-default mb-metal-band"; do
  set -- $pair
  echo "== $1: metal band - default"
  .venv/bin/python scripts/compare_bench_runs.py results/$1-$2 results/$1-$3 --suffix +mb --method prior
  .venv/bin/python scripts/photo_brightness.py results/$1-$3 --against results/$1-$2 --methods prior
done
