#!/usr/bin/env bash
# Choosing the photo fit's objective on validation photos only (never on the scored suites):
# the original suite's 8 validation photos (seeds 400200-400207) and the wide suite's 9 (seed 500200).
# Three objectives, fast preset: today's reflectance prior, the paper's objective, the albedo bounds.
# Resumable: rerun to continue. Waits for another benchmark job of this folder to finish first.
set -euo pipefail
cd "$(dirname "$0")/.."
while pgrep -f run_wide_suite.sh >/dev/null; do sleep 30; done
R=.venv/bin/roomlight
for suite in wide-val photos-val8; do
  [ -d bench/$suite ] || $R bench make-photos --out bench/$suite --n 8 --seed 400200 --res 96x128 --spp 64 \
      --probe-spp 256 --quiet
  $R bench run-photos bench/$suite --out results/$suite-prior --preset fast --eval-spp 64 --methods prior --quiet
  $R bench run-photos bench/$suite --out results/$suite-paper --preset fast --eval-spp 64 --methods prior --quiet \
      --set albedo_prior=0
  $R bench run-photos bench/$suite --out results/$suite-bounds --preset fast --eval-spp 64 --methods prior --quiet \
      --set albedo_prior=0 --set albedo_range=[0.03,0.9]
done
