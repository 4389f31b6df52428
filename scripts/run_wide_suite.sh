#!/usr/bin/env bash
# The wide photo suite's photographs: the scored 24 (bench/wide24, seed 500100) and the 9 validation photos
# (bench/wide-val, seed 500200) that settings are chosen on; never choose on bench/wide24. The captured-light
# photos need `make blender`. Resumable: make-photos keeps the finished photos.
# Then: scripts/run_photo_default_suites.sh (the scored runs) and scripts/run_room_albedo_validation.sh
# (the validation runs).
set -euo pipefail
cd "$(dirname "$0")/.."
R=.venv/bin/roomlight
COMMON=(--suite wide --res 96x128 --spp 64 --probe-spp 256 --quiet)
$R bench make-photos "${COMMON[@]}" --out bench/wide24 --n 24 --seed 500100
$R bench make-photos "${COMMON[@]}" --out bench/wide-val --n 9 --seed 500200
