#!/usr/bin/env bash
# Choosing the photo fit's objective on validation photos only (never on the scored suites):
# the original suite's 8 validation photos (seeds 400200-400207) and the wide suite's 9 (seed 500200).
# Three objectives, fast preset: the reflectance prior (the default when this was run), the paper's objective,
# the albedo bounds.
# Resumable: rerun to continue. Waits for another benchmark job of this folder to finish first.
set -euo pipefail
cd "$(dirname "$0")/.."
while pgrep -f run_wide_suite.sh >/dev/null; do sleep 30; done
source scripts/validation_photos.sh
build_validation_photos
for suite in "${VALIDATION_SUITES[@]}"; do
  run_validation $suite prior --set albedo_prior=0.3
  run_validation $suite paper --set albedo_prior=0
  run_validation $suite bounds --set albedo_prior=0 --set albedo_range=[0.03,0.9]
done
