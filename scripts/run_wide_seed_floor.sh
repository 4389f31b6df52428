#!/usr/bin/env bash
# The wide suite's scored comparison default - paper objective, judged against the fit's own seed-to-seed
# spread (docs/results.md, "The wide photo suite"): the oracle scored again (is the rebuilt suite the
# committed one?), the default fitted again with the records' seed (does
# today's code reproduce the committed records?), then both objectives with another seed (`--set seed=1000`),
# and the comparison with each side averaged over its two seeds; the prior at infinity with both seeds, for
# the 2.5D light's lead over it. ~1 h 30 min on 2 cores, one job at a time (another job beside it
# changes no number, only the time). Resumable.
set -euo pipefail
cd "$(dirname "$0")/.."
R=.venv/bin/roomlight
FIT=(--preset fast --eval-spp 64 --quiet --methods prior)
PAPER=(--set albedo_prior=0 --set room_albedo=0)   # the paper's objective: no reflectance prior, no room bound
REC=benchmarks/results
$R bench make-photos --suite wide --res 96x128 --spp 64 --probe-spp 256 --quiet \
    --out bench/wide24 --n 24 --seed 500100
$R bench run-photos bench/wide24 --out results/wide24-oracle --preset fast --eval-spp 64 --quiet --methods oracle
$R bench run-photos bench/wide24 --out results/wide24-default "${FIT[@]}"
$R bench run-photos bench/wide24 --out results/wide24-seed1000 "${FIT[@]}" --set seed=1000
$R bench run-photos bench/wide24 --out results/wide24-paper-objective-seed1000 "${FIT[@]}" "${PAPER[@]}" --set seed=1000
ENV=(--preset fast --eval-spp 64 --quiet --methods prior-envmap)   # the prior at infinity, both seeds
$R bench run-photos bench/wide24 --out results/wide24-envmap "${ENV[@]}"
$R bench run-photos bench/wide24 --out results/wide24-envmap-seed1000 "${ENV[@]}" --set seed=1000
C=(.venv/bin/python scripts/compare_bench_runs.py)
echo "== the oracle on the rebuilt suite - the committed oracle (zero everywhere: the same photographs)"
"${C[@]}" $REC/wide24-room-bound results/wide24-oracle --suffix +now --method oracle
echo "== today's default - the committed default (same seed: 0 everywhere when it reproduces)"
"${C[@]}" $REC/wide24-room-bound results/wide24-default --suffix +now --method prior
echo "== the default with another seed - the default"
"${C[@]}" results/wide24-default results/wide24-seed1000 --suffix +seed1000 --method prior
echo "== the paper objective with another seed - the paper objective"
"${C[@]}" $REC/wide24-paper-objective results/wide24-paper-objective-seed1000 --suffix +seed1000 --method prior
echo "== default - paper objective, one seed (the committed comparison)"
"${C[@]}" $REC/wide24-paper-objective results/wide24-default --suffix +default --method prior
echo "== default - paper objective, each averaged over seeds 0 and 1000"
"${C[@]}" $REC/wide24-paper-objective,results/wide24-paper-objective-seed1000 \
    results/wide24-default,results/wide24-seed1000 --suffix +default --method prior
echo "== prior - prior-envmap, one seed, both fitted again on the rebuilt suite"
"${C[@]}" results/wide24-envmap results/wide24-default --suffix +x --method prior
echo "== prior-envmap, seed 1000 - seed 0"
"${C[@]}" results/wide24-envmap results/wide24-envmap-seed1000 --suffix +seed1000 --method prior-envmap
echo "== prior - prior-envmap, each averaged over seeds 0 and 1000"
"${C[@]}" results/wide24-envmap,results/wide24-envmap-seed1000 results/wide24-default,results/wide24-seed1000 \
    --suffix +x --method prior
