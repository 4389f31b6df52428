#!/usr/bin/env bash
# Shadow receivers (fit-photo --set shadow_receivers=true), judged on validation photos only: the wide
# suite's 9 (bench/wide-val, seed 500200) and the original suite's 8 (bench/photos-val8, seeds
# 400200-400207), against today's default on the same photos. Builds the validation photos first (make-photos keeps the finished ones).
# Resumable: rerun to continue (run-photos keeps finished photos).
set -euo pipefail
cd "$(dirname "$0")/.."
R=.venv/bin/roomlight
$R bench make-photos --suite wide --res 96x128 --spp 64 --probe-spp 256 \
    --quiet --out bench/wide-val --n 9 --seed 500200
$R bench make-photos --res 96x128 --spp 64 --probe-spp 256 --quiet \
    --out bench/photos-val8 --n 8 --seed 400200
for suite in wide-val photos-val8; do
  $R bench run-photos bench/$suite --out results/$suite-room1 --preset fast --eval-spp 64 --methods prior --quiet
  $R bench run-photos bench/$suite --out results/$suite-receivers --preset fast --eval-spp 64 --methods prior \
      --quiet --set shadow_receivers=true
done
