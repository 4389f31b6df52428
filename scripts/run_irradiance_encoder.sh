#!/usr/bin/env bash
# A view encoder trained to keep the unseen room's energy (irradiance_weight = 1), judged on the validation
# photos of both photo suites against the bundled encoder (same rooms, same schedule, no irradiance term).
# One heavy job at a time; every step resumes. The run's result is kept in training/view-encoder-l512-irr1/.
# Measured on a 2-core machine running at half its usual speed: 51 min of rooms, 26 of training, 20 of
# validation photos, about 6 min per fitted set of photos.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/validation_photos.sh
WEIGHT=${WEIGHT:-1}
RUN=runs/view-encoder-l512-irr$WEIGHT
$R synth --n 2400 --res 64x128 --out data/rooms64b --workers 2            # the bundled encoder's rooms
$R train-view-encoder --model training/prior-l512 --data data/rooms64b --out $RUN \
    --max-steps 2500 --time-budget 60 --set irradiance_weight=$WEIGHT
build_validation_photos
for suite in "${VALIDATION_SUITES[@]}"; do
  run_validation $suite room1                                                # the bundled encoder
  run_validation $suite start --set iterations=0
  run_validation $suite irr$WEIGHT --view-encoder $RUN/best
  run_validation $suite irr$WEIGHT-start --view-encoder $RUN/best --set iterations=0
done
