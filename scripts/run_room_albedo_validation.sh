#!/usr/bin/env bash
# The visible room's albedo bound (fit-photo --set room_albedo=W), chosen on validation photos only: the
# wide suite's 9 (bench/wide-val, seed 500200) and the original suite's 8 (bench/photos-val8, seeds
# 400200-400207), against the objectives of scripts/run_objective_validation.sh. Resumable: rerun to continue.
# (The room1 runs let the bound move the whole light, room_albedo_moves=light; room1e its exposure only.)
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/validation_photos.sh
run() { run_validation "$@"; }
PAPER=(--set albedo_prior=0)
run wide-val room1 "${PAPER[@]}" --set room_albedo=1 --set room_albedo_moves=light
run photos-val8 paper "${PAPER[@]}"
run photos-val8 room1 "${PAPER[@]}" --set room_albedo=1 --set room_albedo_moves=light
run wide-val room1e "${PAPER[@]}" --set room_albedo=1 --set room_albedo_moves=exposure
run photos-val8 room1e "${PAPER[@]}" --set room_albedo=1 --set room_albedo_moves=exposure
run photos-val8 prior --set albedo_prior=0.3
