#!/usr/bin/env bash
# A candidate view encoder against the bundled one: trained on the bundled encoder's rooms with its schedule
# and the given training settings, then judged
#   1. on the 96 validation views of benchmarks/view_encoder_depth.py (the decoded room against the truth);
#   2. on validation photos only (bench/wide-val-clean, bench/photos-val8-hr at its 192 x 256 px,
#      bench/wide-val-realmetal), fit seeds 0 and 1000, each side averaged over the two seeds before pairing.
#
#   scripts/run_view_encoder_candidate.sh NAME [--set FIELD=VALUE ...]    # training settings of the candidate
#   scripts/run_view_encoder_candidate.sh disp30 --set display_weight=30  # the display term (docs/results.md)
#   scripts/run_view_encoder_candidate.sh lat0 --set latent_weight=0      # no pull towards the encoder's means
#
# The bundled encoder's runs on those sets are the defaults' records (results/*-mb-default, *-default,
# *-seed1000). The photos are built by scripts/run_hires_validation.sh and scripts/run_real_metal_validation.sh;
# the bundled encoder's seed-1000 fit of wide-val-realmetal is made below if it is missing. One heavy job at a
# time; every step resumes (ONLY_VIEWS=1 stops after the validation views). Measured for disp30: 22 min of
# rooms, 20 of training, 27 of validation fits.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ $# -lt 1 ]; then echo "usage: $0 NAME [--set FIELD=VALUE ...]" >&2; exit 2; fi
NAME=$1; shift
source scripts/validation_photos.sh   # R, run_validation
RUN=runs/view-encoder-l512-$NAME
$R synth --n 2400 --res 64x128 --out data/rooms64b --workers 2            # the bundled encoder's rooms
$R train-view-encoder --model training/prior-l512 --data data/rooms64b --out $RUN \
    --max-steps 2500 --time-budget 60 "$@"
.venv/bin/python benchmarks/view_encoder_depth.py --data data/rooms64b --views 96 \
    --encoder bundled=src/roomlight/assets/prior/view_encoder --encoder $NAME=$RUN/best --out results/view-encoder-$NAME.json
if [ "${ONLY_VIEWS:-0}" = 1 ]; then exit 0; fi
hr=(--set render_size=256 --set geometry_size=512)
enc=(--view-encoder $RUN/best)
run_validation wide-val-clean $NAME "${enc[@]}"
run_validation photos-val8-hr $NAME "${hr[@]}" "${enc[@]}"
run_validation wide-val-realmetal $NAME "${enc[@]}"
run_validation wide-val-realmetal seed1000 --set seed=1000             # the bundled encoder's (kept if present)
run_validation wide-val-clean $NAME-seed1000 "${enc[@]}" --set seed=1000
run_validation photos-val8-hr $NAME-seed1000 "${hr[@]}" "${enc[@]}" --set seed=1000
run_validation wide-val-realmetal $NAME-seed1000 "${enc[@]}" --set seed=1000
for pair in "wide-val-clean mb-default lr-seed1000" "photos-val8-hr mb-default seed1000" \
            "wide-val-realmetal default seed1000"; do
  set -- $pair
  echo "== $1: $NAME - bundled encoder (seed 0)"
  .venv/bin/python scripts/compare_bench_runs.py results/$1-$2 results/$1-$NAME --suffix +$NAME --method prior
  .venv/bin/python scripts/photo_brightness.py results/$1-$NAME --against results/$1-$2 --methods prior
  echo "== $1: $NAME - bundled encoder, each averaged over seeds 0 and 1000"
  .venv/bin/python scripts/compare_bench_runs.py results/$1-$2,results/$1-$3 \
      results/$1-$NAME,results/$1-$NAME-seed1000 --suffix +$NAME --method prior
done
