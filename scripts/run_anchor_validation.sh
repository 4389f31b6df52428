#!/usr/bin/env bash
# The latent anchor (fit-photo --set z_anchor=W: a pull of z towards the view encoder's start) on the
# validation photos of both photo suites, against today's default, one heavy job at a time.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/validation_photos.sh
build_validation_photos
for suite in "${VALIDATION_SUITES[@]}"; do run_validation $suite room1; done
for w in 1e-3 1e-2; do
  for suite in "${VALIDATION_SUITES[@]}"; do run_validation $suite anchor$w --set z_anchor=$w; done
done
