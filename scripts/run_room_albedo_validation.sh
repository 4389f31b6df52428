#!/usr/bin/env bash
# The visible room's albedo bound (fit-photo --set room_albedo=W), chosen on validation photos only: the
# wide suite's 9 (bench/wide-val, seed 500200) and the original suite's 8 (bench/photos-val8, seeds
# 400200-400207), against the objectives of scripts/run_objective_validation.sh. Resumable: rerun to continue.
set -euo pipefail
cd "$(dirname "$0")/.."
R=.venv/bin/roomlight
run() {  # run SUITE NAME SETTINGS...
  local suite=$1 name=$2; shift 2
  $R bench run-photos bench/$suite --out results/$suite-$name --preset fast --eval-spp 64 --methods prior --quiet "$@"
}
PAPER=(--set albedo_prior=0)
BOUNDS=(--set albedo_prior=0 --set "albedo_range=[0.03,0.9]")
run wide-val room1 "${PAPER[@]}" --set room_albedo=1
run photos-val8 paper "${PAPER[@]}"
run photos-val8 room1 "${PAPER[@]}" --set room_albedo=1
run photos-val8 prior
run wide-val bounds-room1 "${BOUNDS[@]}" --set room_albedo=1
run photos-val8 bounds "${BOUNDS[@]}"
run photos-val8 bounds-room1 "${BOUNDS[@]}" --set room_albedo=1
