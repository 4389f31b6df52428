#!/usr/bin/env bash
# The visible room's albedo bound moving the light's level only (room_albedo_moves=exposure) against moving
# the whole light (the default), and both against the paper's objective, on the validation photos only:
# the wide suite's 9 (bench/wide-val, seed 500200) and the original suite's 8 (bench/photos-val8, seeds
# 400200-400207). The question is the colour error: a change of level cannot turn a probe's colour.
# Resumable: rerun to continue.
set -euo pipefail
cd "$(dirname "$0")/.."
R=.venv/bin/roomlight
[ -d bench/wide-val ] || $R bench make-photos --suite wide --res 96x128 --spp 64 --probe-spp 256 --insert-spp 0 \
    --quiet --out bench/wide-val --n 9 --seed 500200
[ -d bench/photos-val8 ] || $R bench make-photos --out bench/photos-val8 --n 8 --seed 400200 --res 96x128 --spp 64 \
    --probe-spp 256 --insert-spp 0 --quiet
run() {  # run SUITE NAME SETTINGS...
  local suite=$1 name=$2; shift 2
  $R bench run-photos bench/$suite --out results/$suite-$name --preset fast --eval-spp 64 --methods prior --quiet "$@"
}
for suite in wide-val photos-val8; do
  run $suite room1 --set albedo_prior=0 --set room_albedo=1 --set room_albedo_moves=light
  run $suite room1e --set albedo_prior=0 --set room_albedo=1 --set room_albedo_moves=exposure
  run $suite paper --set albedo_prior=0 --set room_albedo=0
done
