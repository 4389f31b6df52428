#!/usr/bin/env bash
# Too dim a light, search or objective? The photo fit started from the prior's own latent for the true
# room (benchmarks/level_diagnosis.py) on the 17 validation photos of both photo suites, against the
# default fit, one heavy job at a time. Builds the validation sets and the default runs if missing.
set -euo pipefail
cd "$(dirname "$0")/.."
R=.venv/bin/roomlight
[ -d bench/photos-val8 ] || $R bench make-photos --res 96x128 --spp 64 --probe-spp 256 --quiet \
    --out bench/photos-val8 --n 8 --seed 400200
[ -d bench/wide-val ] || $R bench make-photos --suite wide --res 96x128 --spp 64 --probe-spp 256 --quiet \
    --out bench/wide-val --n 9 --seed 500200
for suite in wide-val photos-val8; do
  $R bench run-photos bench/$suite --out results/$suite-room1 --preset fast --eval-spp 64 \
      --methods prior,prior-ceiling --quiet
  .venv/bin/python benchmarks/level_diagnosis.py bench/$suite --out results/$suite-from-ceiling \
      --against results/$suite-room1 --preset fast --eval-spp 64 | tee results/$suite-from-ceiling.md
done
