#!/usr/bin/env bash
# The bundled prior's depth-optional view encoder (docs/photo.md, "The view encoder"): the training rooms of
# the bundled view encoder, then the same schedule with depth withheld from half the views, then its scores
# against the depth-trained encoder on the validation rooms. One heavy job at a time; resumable (synth keeps
# finished rooms, training continues from its newest checkpoint).
set -euo pipefail
cd "$(dirname "$0")/.."
R=.venv/bin/roomlight
$R synth --n 2400 --res 64x128 --out data/rooms64b --workers 2
$R train-view-encoder --model src/roomlight/assets/prior --data data/rooms64b --out runs/view-encoder-l512-depth-optional \
    --max-steps 2500 --set depth_dropout=0.5
.venv/bin/python benchmarks/view_encoder_depth.py --data data/rooms64b \
    --encoder bundled=src/roomlight/assets/prior/view_encoder \
    --encoder depth-optional=runs/view-encoder-l512-depth-optional/best --out results/view-encoder-depth.json \
    > results/view-encoder-depth.md
