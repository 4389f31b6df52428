# Sourced by the scripts/run_*validation*.sh scripts: the photo fit's validation photos and how a setting
# is judged on them. Never run on the scored suites (bench/photos24, bench/wide24).
#
#   build_validation_photos     the wide suite's 9 (bench/wide-val, seed 500200) and the original suite's 8
#                               (bench/photos-val8, seeds 400200-400207), with their clean insertion truth;
#                               make-photos keeps the photos already built, so this is cheap when they exist
#   build_real_metal_photos     9 more of the wide suite (bench/wide-val-realmetal, seed 500300) whose metals
#                               have real metals' reflectance (`--set metal_colours=real`): the suites' own
#                               metals are mostly darker than any real one, so a setting that assumes real
#                               metals is judged here too
#   run_validation SUITE NAME [--set FIELD=VALUE ...] [--methods M]
#                               fit-photo's `fast` preset on SUITE's photos, probes at 64 spp, into
#                               results/SUITE-NAME (resumable: finished photos are kept)
R=.venv/bin/roomlight
VALIDATION_SUITES=(wide-val photos-val8)

build_validation_photos() {
  $R bench make-photos --suite wide --res 96x128 --spp 64 --probe-spp 256 --quiet \
      --out bench/wide-val --n 9 --seed 500200
  $R bench make-photos --res 96x128 --spp 64 --probe-spp 256 --quiet \
      --out bench/photos-val8 --n 8 --seed 400200
}

build_real_metal_photos() {
  $R bench make-photos --suite wide --res 96x128 --spp 64 --probe-spp 256 --quiet \
      --out bench/wide-val-realmetal --n 9 --seed 500300 --set metal_colours=real
}

run_validation() {
  local suite=$1 name=$2; shift 2
  local methods=prior
  if [ "${1:-}" = "--methods" ]; then methods=$2; shift 2; fi
  $R bench run-photos bench/$suite --out results/$suite-$name --preset fast --eval-spp 64 --methods "$methods" \
      --quiet "$@"
}
