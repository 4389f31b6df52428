#!/usr/bin/env bash
# A view encoder trained to keep the unseen room's energy (irradiance_weight = 1), judged on the validation
# photos of both photo suites against the bundled encoder (same rooms, same schedule, no irradiance term).
# SEEN=1: the irradiance compared after the seen-part exposure match (irradiance_seen_matched), run irr1-seen.
# One heavy job at a time; every step resumes. The runs' results are kept in training/view-encoder-l512-irr1*/.
# Measured on a 2-core machine running at half its usual speed: 51 min of rooms, 26 of training, 20 of
# validation photos, about 6 min per fitted set of photos.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/validation_photos.sh
WEIGHT=${WEIGHT:-1}
NAME=irr$WEIGHT
MATCH=()
if [ "${SEEN:-0}" = 1 ]; then NAME=irr$WEIGHT-seen; MATCH=(--set irradiance_seen_matched=true); fi
RUN=runs/view-encoder-l512-$NAME
$R synth --n 2400 --res 64x128 --out data/rooms64b --workers 2            # the bundled encoder's rooms
$R train-view-encoder --model training/prior-l512 --data data/rooms64b --out $RUN \
    --max-steps 2500 --time-budget 60 --set irradiance_weight=$WEIGHT "${MATCH[@]}"
build_validation_photos
for suite in "${VALIDATION_SUITES[@]}"; do
  run_validation $suite room1                                                # the bundled encoder
  run_validation $suite start --set iterations=0
  run_validation $suite $NAME --view-encoder $RUN/best
  run_validation $suite $NAME-start --view-encoder $RUN/best --set iterations=0
done
