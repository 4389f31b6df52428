#!/usr/bin/env bash
# The Gaussian prior's weight on z (fit-photo --set z_prior=W, default 1e-4) on the validation photos of
# both photo suites: off (the paper gives none) and ten times stronger, against today's default, one heavy
# job at a time. Resumable: rerun to continue.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/validation_photos.sh
build_validation_photos
for suite in "${VALIDATION_SUITES[@]}"; do run_validation $suite room1; done
for w in 0 1e-3; do
  for suite in "${VALIDATION_SUITES[@]}"; do run_validation $suite zprior$w --set z_prior=$w; done
done
