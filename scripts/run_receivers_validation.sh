#!/usr/bin/env bash
# Shadow receivers (fit-photo --set shadow_receivers=true), judged on the validation photos of both photo
# suites against today's default on the same photos. Resumable: rerun to continue.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/validation_photos.sh
build_validation_photos
for suite in "${VALIDATION_SUITES[@]}"; do
  run_validation $suite room1
  run_validation $suite receivers --set shadow_receivers=true
done
