#!/usr/bin/env bash
# Does the photo fit read the light better from a larger or a cleaner photograph, do the shadow receivers
# (which lost on the 64-spp validation photos) pay on photographs with less render noise, and how far does
# the fit move with its own random numbers (--set seed)?
# Validation photos only (seeds 500200 and 400200), never the scored suites:
#   bench/wide-val-clean  the wide suite's validation scenes at the benchmark's 96 x 128 px but 256 spp
#                         (the same scenes as bench/wide-val: staging depends on the frame's size, not on
#                         the samples);
#   bench/photos-val8-hr, bench/wide-val-hr
#                         both suites' validation seeds at make-photos' own 192 x 256 px and 256 spp (other
#                         scenes than bench/wide-val's and bench/photos-val8's: staging checks that each
#                         object shows enough whole pixels, so a larger frame accepts other draws).
# Fits: the `fast` preset, probes at 64 spp; NAME starting with lr- fits at the preset's own 128 / 256
# (render_size / geometry_size: a 192 x 256 photo averaged down to 96 x 128), otherwise at the photo's full
# size (256 / 512). Resumable: rerun to continue (3-10 min to build a suite, 5-9 min per fit setting; about
# 100 min in all on 2 cores). Run it on an otherwise idle machine: beside another CPU-heavy job the same fit can
# land elsewhere (docs/troubleshooting.md).
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/validation_photos.sh   # R, run_validation
run() {  # SUITE NAME [--set FIELD=VALUE ...]
  local suite=$1 name=$2; shift 2
  local size=(--set render_size=256 --set geometry_size=512)
  if [[ $name == lr-* ]]; then size=(); fi
  run_validation "$suite" "$name" "${size[@]}" "$@"
}
compare() {  # SUITE BASE OTHER
  .venv/bin/python scripts/compare_bench_runs.py results/$1-$2 results/$1-$3 --suffix +$3 --method prior
  .venv/bin/python scripts/photo_brightness.py results/$1-$3 --against results/$1-$2
}
$R bench make-photos --suite wide --res 96x128 --spp 256 --probe-spp 256 --quiet \
    --out bench/wide-val-clean --n 9 --seed 500200
run wide-val-clean lr-default
run wide-val-clean lr-receivers --set shadow_receivers=true
run wide-val-clean lr-seed1000 --set seed=1000      # the fit's own random numbers: what "no change" looks like
$R bench make-photos --res 192x256 --spp 256 --probe-spp 256 --insert-spp 1024 --quiet \
    --out bench/photos-val8-hr --n 8 --seed 400200
run photos-val8-hr default
run photos-val8-hr receivers --set shadow_receivers=true
run photos-val8-hr seed1000 --set seed=1000
$R bench make-photos --suite wide --res 192x256 --spp 256 --probe-spp 256 --insert-spp 1024 --quiet \
    --out bench/wide-val-hr --n 9 --seed 500200
run wide-val-hr default
run wide-val-hr receivers --set shadow_receivers=true
run wide-val-hr lr-default
run wide-val-hr lr-receivers --set shadow_receivers=true
echo "== wide-val-clean (96 x 128, 256 spp): receivers - default"; compare wide-val-clean lr-default lr-receivers
echo "== wide-val-clean: the default with another seed - the default"; compare wide-val-clean lr-default lr-seed1000
echo "== photos-val8-hr (192 x 256): receivers - default";        compare photos-val8-hr default receivers
echo "== photos-val8-hr: the default with another seed - the default"; compare photos-val8-hr default seed1000
echo "== wide-val-hr: fitted at 192 x 256 - at 96 x 128";          compare wide-val-hr lr-default default
echo "== wide-val-hr (192 x 256): receivers - default";           compare wide-val-hr default receivers
echo "== wide-val-hr (96 x 128): receivers - default";            compare wide-val-hr lr-default lr-receivers
echo "== the light averaged over the two seeds' fits - its members"
.venv/bin/python scripts/seed_ensemble.py results/wide-val-clean-lr-default results/wide-val-clean-lr-seed1000
.venv/bin/python scripts/seed_ensemble.py results/photos-val8-hr-default results/photos-val8-hr-seed1000
