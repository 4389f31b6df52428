#!/usr/bin/env bash
# Both photo suites under today's photo-fit defaults, against the paper's objective, paired per photo
# (docs/results.md, "The wide photo suite" and "The photo benchmark"), then the inserted objects' study
# (scripts/run_insertion_study.sh) and diagnosis. One heavy job at a time, in the order the comparisons
# need them (the fitted prior under both objectives first, then the other methods); resumable: rerun to
# continue. Builds bench/wide24 and bench/photos24 first, with the records' seeds (make-photos keeps the
# finished photos; the wide suite's captured light needs `make blender`).
set -euo pipefail
cd "$(dirname "$0")/.."
R=.venv/bin/roomlight
FIT=(--preset fast --eval-spp 64 --quiet)
PAPER=(--set albedo_prior=0 --set room_albedo=0)   # the paper's objective: no reflectance prior, no room bound
$R bench make-photos --suite wide --res 96x128 --spp 64 --probe-spp 256 --quiet \
    --out bench/wide24 --n 24 --seed 500100
$R bench run-photos bench/wide24 --out results/wide24-room-bound "${FIT[@]}" --methods prior
$R bench run-photos bench/wide24 --out results/wide24-paper-objective "${FIT[@]}" --methods prior "${PAPER[@]}"
$R bench run-photos bench/wide24 --out results/wide24-room-bound "${FIT[@]}" \
    --methods prior,oracle,oracle-envmap,naive-paste,prior-envmap,direct-envmap
$R bench make-photos --out bench/photos24 --n 24 --seed 400100 --res 96x128 \
    --spp 64 --probe-spp 256 --quiet
$R bench run-photos bench/photos24 --out results/photos24-room-bound "${FIT[@]}" --methods prior
$R bench run-photos bench/photos24 --out results/photos24-paper-objective "${FIT[@]}" --methods prior "${PAPER[@]}"
$R bench run-photos bench/photos24 --out results/photos24-room-bound "${FIT[@]}" \
    --methods prior,oracle,oracle-envmap,naive-paste,prior-envmap
scripts/run_insertion_study.sh
.venv/bin/python benchmarks/insertion_diagnosis.py bench/photos24 --photos 8 --out results/insertion-diagnosis.json \
    > results/insertion-diagnosis.md
$R bench run-photos bench/photos24 --out results/photos24-room-bound "${FIT[@]}" \
    --methods prior,prior-envmap,direct-envmap,oracle,oracle-envmap,naive-paste
