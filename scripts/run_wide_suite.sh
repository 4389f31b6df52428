#!/usr/bin/env bash
# The wide photo suite, built and fitted one heavy job at a time (resumable: rerun to continue).
# Scored photos: bench/wide24 (seed 500100); validation photos: bench/wide-val (seed 500200), for choosing
# settings; never choose on bench/wide24. Results go to results/wide24-*.
set -euo pipefail
cd "$(dirname "$0")/.."
R=.venv/bin/roomlight
COMMON=(--suite wide --res 96x128 --spp 64 --probe-spp 256 --quiet)
$R bench make-photos "${COMMON[@]}" --out bench/wide24 --n 24 --seed 500100
$R bench make-photos "${COMMON[@]}" --out bench/wide-val --n 9 --seed 500200
$R bench run-photos bench/wide24 --out results/wide24-default --preset fast --eval-spp 64 --quiet \
    --methods prior,prior-envmap,direct-envmap,oracle,oracle-envmap,naive-paste
$R bench run-photos bench/wide24 --out results/wide24-paper-objective --preset fast --eval-spp 64 --quiet \
    --methods prior --set albedo_prior=0
$R bench report-photos results/wide24-default --no-figures
$R bench report-photos results/wide24-paper-objective --no-figures
