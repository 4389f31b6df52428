#!/usr/bin/env bash
# The wide suite's validation photos with real metals (bench/wide-val-realmetal: 9 photos, seed 500300,
# every metal's base colour a real metal's reflectance), built and fitted with fit-photo's defaults into
# results/wide-val-realmetal-default: the baseline against which a setting that assumes real metals is
# judged (with the other validation photos). ~1 min a photo to build, ~1 min a photo to fit; resumable.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/validation_photos.sh
build_real_metal_photos
run_validation wide-val-realmetal default
.venv/bin/python scripts/photo_brightness.py results/wide-val-realmetal-default --methods prior
