#!/usr/bin/env bash
# The latent anchor (a pull of z towards the view encoder's start) on the 17 validation photos of both
# photo suites, against today's default, one heavy job at a time. Builds the validation sets if missing.
set -euo pipefail
cd "$(dirname "$0")/.."
R=.venv/bin/roomlight
[ -d bench/photos-val8 ] || $R bench make-photos --res 96x128 --spp 64 --probe-spp 256 --quiet \
    --out bench/photos-val8 --n 8 --seed 400200
[ -d bench/wide-val ] || $R bench make-photos --suite wide --res 96x128 --spp 64 --probe-spp 256 --quiet \
    --out bench/wide-val --n 9 --seed 500200
for suite in wide-val photos-val8; do
  $R bench run-photos bench/$suite --out results/$suite-room1 --preset fast --eval-spp 64 --methods prior --quiet
done
for w in 1e-3 1e-2; do
  for suite in wide-val photos-val8; do
    $R bench run-photos bench/$suite --out results/$suite-anchor$w --preset fast --eval-spp 64 --methods prior \
        --quiet --set z_anchor=$w
  done
done
