#!/usr/bin/env bash
# Both photo suites under today's photo-fit defaults, against the paper's objective, paired per photo
# (docs/results.md, "The wide photo suite" and "The photo benchmark"), then the inserted objects' study
# (scripts/run_insertion_study.sh) and diagnosis. One heavy job at a time; resumable: rerun to continue. Needs
# bench/photos24 and bench/wide24 (scripts/run_wide_suite.sh and the make-photos command in docs/results.md).
set -euo pipefail
cd "$(dirname "$0")/.."
R=.venv/bin/roomlight
FIT=(--preset fast --eval-spp 64 --quiet)
PAPER=(--set albedo_prior=0 --set room_albedo=0)   # the paper's objective: no reflectance prior, no room bound
$R bench run-photos bench/wide24 --out results/wide24-defaults "${FIT[@]}" \
    --methods prior,prior-envmap,direct-envmap,oracle,oracle-envmap,naive-paste
$R bench run-photos bench/wide24 --out results/wide24-paper-objective "${FIT[@]}" --methods prior "${PAPER[@]}"
$R bench run-photos bench/photos24 --out results/photos24-defaults "${FIT[@]}" --methods prior,prior-envmap
$R bench run-photos bench/photos24 --out results/photos24-paper-objective "${FIT[@]}" --methods prior "${PAPER[@]}"
scripts/run_insertion_study.sh
.venv/bin/python benchmarks/insertion_diagnosis.py bench/photos24 --photos 8 --out results/insertion-diagnosis.json \
    > results/insertion-diagnosis.md
$R bench run-photos bench/photos24 --out results/photos24-defaults "${FIT[@]}" \
    --methods prior,prior-envmap,direct-envmap,oracle,oracle-envmap,naive-paste
