#!/usr/bin/env bash
# The visible room's albedo bound moving the light's level only (room_albedo_moves=exposure) against moving
# the whole light (the default), and both against the paper's objective, on the validation photos only:
# the wide suite's 9 (bench/wide-val, seed 500200) and the original suite's 8 (bench/photos-val8, seeds
# 400200-400207). The question is the colour error: a change of level cannot turn a probe's colour.
# Resumable: rerun to continue.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/validation_photos.sh
build_validation_photos
run() { run_validation "$@"; }
for suite in wide-val photos-val8; do
  run $suite room1 --set albedo_prior=0 --set room_albedo=1 --set room_albedo_moves=light
  run $suite room1e --set albedo_prior=0 --set room_albedo=1 --set room_albedo_moves=exposure
  run $suite paper --set albedo_prior=0 --set room_albedo=0
done
