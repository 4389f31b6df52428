#!/usr/bin/env bash
# Too dim a light, search or objective? On the validation photos of both photo suites, one heavy job at a
# time: the default fit with the prior's ceiling beside it, the start alone (iterations=0), the fit started 2.8x brighter
# (start_exposure_ev=1.5), and the fit started from the prior's own latent for the true room
# (benchmarks/level_diagnosis.py, its per-photo table kept in results/SUITE-from-ceiling.md).
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/validation_photos.sh
build_validation_photos
for suite in "${VALIDATION_SUITES[@]}"; do
  run_validation $suite room1 --methods prior,prior-ceiling
  run_validation $suite start --set iterations=0
  run_validation $suite ev1.5 --set start_exposure_ev=1.5
  .venv/bin/python benchmarks/level_diagnosis.py bench/$suite --out results/$suite-from-ceiling \
      --against results/$suite-room1 --preset fast --eval-spp 64 | tee results/$suite-from-ceiling.md
done
