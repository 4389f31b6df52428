"""Too dim a light: where the photo fit's search stops, or what its objective prefers?

On many photographs the fitted prior lights the probes at a fraction of the true level (docs/results.md,
"Which photos fail and why"). Two explanations predict different things:

- **search**: the objective has a better minimum at the true level, and the fit does not reach it from
  where it starts (the view encoder's latent, the background-matched exposure);
- **objective**: at the true level the objective is no lower, so no start or longer fit finds it.

This script runs the photo fit of the ``prior`` method once more on every photo of a benchmark, from
the best start the prior can be given: the prior's own latent for the whole true room (the
``prior-ceiling`` reference: the oracle panorama fitted by the latent, which lights the probes at about the
true level) in the oracle's frame, its exposure that panorama's. Everything else is the preset's. The
run is an ordinary results folder (``--out``), scored as ``bench run-photos`` scores. Against a run of the
default fit (``--against``, with ``prior`` and ``prior-ceiling`` in it), per photo:

- the light's level at the probes over the truth's (the geometric mean of the diffuse probes' ratio, as
  ``scripts/photo_brightness.py`` computes it) for the ceiling, the default fit and the fit from the ceiling;
- the best fixed-seed objective of both fits (the same photograph, preset and noise seeds: comparable) and
  its terms at the end.

If the fit from the ceiling stays at the true level with a lower objective, the search is to blame; if it
drifts dim, or stays bright with a higher objective, the objective is.

Run: .venv/bin/python benchmarks/level_diagnosis.py BENCH --out results/X-from-ceiling --against results/X
         [--preset fast] [--eval-spp 64] [--set FIELD=VALUE ...]
Resumable (finished photos are skipped, as in ``bench run-photos``).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent


def fit_from_ceiling(case_dir, method, preset, out_dir, model=None, progress=False, overrides=None) -> dict:
    """The benchmark's fit function (see ``roomlight.evaluation.photobench.adapter.fit_photo_case``) with the
    prior's light started at its ceiling latent, in the oracle's frame."""
    import time

    import torch

    from roomlight.evaluation.photobench.adapter import finished_fit
    from roomlight.evaluation.photobench.ceiling import prior_ceiling_latent
    from roomlight.evaluation.photobench.scoring import load_truth
    from roomlight.fitting.inverse.lights import PriorLight
    from roomlight.fitting.photo import case as case_mod
    from roomlight.fitting.photo import config as config_mod
    from roomlight.fitting.photo import fitter as fitter_mod
    from roomlight.fitting.photo.geometry import SceneTransform

    assert method == "prior", method
    t0 = time.perf_counter()
    config = config_mod.photo_config(preset, **dict(overrides or {}))
    case = case_mod.load_photo(str(case_dir), min_object_fraction=config.min_object_fraction)
    res, exposure_factor, frame = prior_ceiling_latent(case_dir, model, load_truth(case_dir))
    light = PriorLight(model, envmap=False, init_exposure=1.0, z_prior=config.z_prior, z_anchor=config.z_anchor)
    with torch.no_grad():
        light.z.copy_(res.z[0])
        light.s.fill_(math.log(exposure_factor))
    light.anchor_here()
    transform = SceneTransform.from_matrix(frame, "oracle frame")
    fit = fitter_mod.fit_photo(case, method, config, model=model, out_dir=Path(out_dir), progress=progress,
                               light=light, transform=transform)
    return finished_fit(fit, case, config, out_dir, t0)


def brightness(results: Path, methods: list[str]) -> dict[str, dict[str, float]]:
    """Method -> photo -> the light's level at the diffuse probes over the truth's (scripts/photo_brightness.py)."""
    sys.path.insert(0, str(ROOT / "scripts"))
    from photo_brightness import brightness_table

    return {m: dict(zip(t["photos"], t["ratio"])) for m, t in brightness_table(results, methods).items()}


def fit_record(results: Path, photo: str) -> dict | None:
    f = results / "cases" / photo / "prior" / "fit" / "result.json"
    return json.loads(f.read_text()) if f.is_file() else None


def report(out: Path, against: Path) -> str:
    mine = brightness(out, ["prior"])["prior"]
    levels = brightness(against, ["prior", "prior-ceiling"])
    theirs, ceiling = levels["prior"], levels["prior-ceiling"]
    rows = ["| photo | level / truth: ceiling, default fit, fit from the ceiling | objective: default, from the "
            "ceiling | image term: default, from the ceiling |", "|---|:---:|:---:|:---:|"]
    deltas, lower = [], 0
    for photo in sorted(mine):
        a, b = fit_record(against, photo), fit_record(out, photo)
        if a is None or b is None or photo not in theirs:
            continue
        la, lb = a["best_fixed_seed_loss"], b["best_fixed_seed_loss"]
        deltas.append(lb - la)
        lower += lb < la
        rows.append(f"| {photo} | {ceiling.get(photo, float('nan')):.2f}, {theirs[photo]:.2f}, {mine[photo]:.2f} | "
                    f"{la:.4f}, {lb:.4f} | {a['objective'].get('img', float('nan')):.4f}, "
                    f"{b['objective'].get('img', float('nan')):.4f} |")
    if deltas:
        g = lambda d: math.exp(np.mean(np.log([d[p] for p in mine if p in theirs])))  # noqa: E731
        rows.append(f"\nGeometric mean level: default {g(theirs):.2f}, from the ceiling {g(mine):.2f}; "
                    f"the fit from the ceiling ends at a lower objective on {lower} of {len(deltas)} photos "
                    f"(mean difference {np.mean(deltas):+.4f}).")
    return "\n".join(rows)


def main(argv=None) -> int:
    from roomlight.cli.common import parse_sets
    from roomlight.demo import bundled_prior_path
    from roomlight.evaluation.photobench.runner import run_photo_benchmark
    from roomlight.prior.model import PanoVAE

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("bench", type=Path)
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--against", type=Path, required=True, help="a run with prior and prior-ceiling")
    ap.add_argument("--preset", default="fast")
    ap.add_argument("--eval-spp", type=int, default=64)
    ap.add_argument("--set", dest="sets", action="append", default=[], metavar="FIELD=VALUE")
    args = ap.parse_args(argv)
    model = PanoVAE.from_pretrained(bundled_prior_path())
    summary = run_photo_benchmark(args.bench, args.out, ["prior"], args.preset, model, args.eval_spp,
                                  fit=fit_from_ceiling, model_name="bundled prior, started at its ceiling",
                                  overrides=parse_sets(args.sets))
    if summary.failed:
        print(f"failed: {summary.failed}", file=sys.stderr)
    print(report(args.out, args.against))
    return 0


if __name__ == "__main__":
    sys.exit(main())
