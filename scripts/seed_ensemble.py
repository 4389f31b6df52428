"""Is a photo fit's error the seed's or the photograph's? Several fits' predictions averaged, scored.

Two or more `roomlight bench run-photos` runs of the same photos and method that differ only in the fit's
seed (`--set seed=N`) give several lights per photo, and so several predictions of how the probes look.
Their average is the ensemble's prediction: the probes' appearance averaged over the fits (not one light:
each fit has its own 2.5D shape, and two meshes in one scene would hide each other). If the fits erred
independently around the truth, their average would score clearly better than each of them (the spread
shrinks as 1/K); if it scores as they do, the error is shared: it is what the photograph and the objective
give, not the seed.

The probe renders of a run are all made with the benchmark's one scoring seed, so the members' render
noise is alike and averaging them removes little of it: the difference measures the fits, not the samples.

Prints, per probe material, each run's mean PSNR LDR and angular error, the averaged prediction's, and the
paired difference average − mean of the members per photo (mean, 95 % bootstrap interval, photos won).

Run: .venv/bin/python scripts/seed_ensemble.py RUN RUN [RUN ...] [--method prior] [--json FILE]
     (each RUN a `roomlight bench run-photos` folder whose cases still hold their probe renders)
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

MATERIALS = ("diffuse", "matte", "mirror")
SCORES = ("psnr_ldr", "angular_error")


def ensemble_scores(runs: list[Path], method: str) -> dict:
    """``{photo: {material: {"members": [{score: value}], "average": {score: value}}}}`` over the photos every
    run finished; the average is the members' probe renders averaged. Refuses runs whose photos of one name
    are not the same photograph."""
    from roomlight.evaluation.harness.metrics import score_view
    from roomlight.evaluation.photobench.case import read_rgb_exr
    from roomlight.evaluation.photobench.scoring import load_truth

    def finished(run: Path) -> set[str]:
        cases = run / "cases"
        if not cases.is_dir():
            raise SystemExit(f"{run}: not a run-photos folder (no cases/)")
        return {d.name for d in cases.iterdir() if (d / method / "result.json").is_file()}

    if len(set(Path(r).resolve() for r in runs)) < len(runs):
        raise SystemExit("a run is given twice")
    photos = sorted(set.intersection(*(finished(r) for r in runs)))
    if not photos:
        raise SystemExit(f"no photo has a finished {method!r} case in every run")
    out = {}
    for photo in photos:
        folders = [r / "cases" / photo / method for r in runs]
        sources = {str(json.loads((f / "result.json").read_text())["case_dir"]) for f in folders}
        if len(sources) > 1:
            raise SystemExit(f"{photo}: the runs fitted different photographs ({', '.join(sorted(sources))})")
        truth = load_truth(sources.pop())
        mask = truth.window_mask > 0
        out[photo] = {}
        for m in MATERIALS:
            renders = [read_rgb_exr(f / f"probes_{m}.exr") for f in folders]
            gt = truth.probe_images[m]
            members = [score_view(r, gt, mask) for r in renders]
            average = score_view(np.mean(renders, axis=0), gt, mask)
            out[photo][m] = {"members": [{s: float(x[s]) for s in SCORES} for x in members],
                             "average": {s: float(average[s]) for s in SCORES}}
    return out


def summary(scores: dict) -> dict:
    """Per material and score: each member run's mean over photos (``members``), the average's
    (``average``), and the paired difference average − the members' mean per photo (``mean``, ``ci95``,
    ``wins``, ``n``; photos where either is not finite are left out)."""
    from roomlight.evaluation.harness.paired import mean_over_runs, paired_differences

    def record(photo, m, name, values):
        return {"scene": photo, "material": m, "method": name, "metrics": {"eval": values}}

    runs = len(next(iter(scores.values()))[MATERIALS[0]]["members"])
    average = [record(p, m, "average", scores[p][m]["average"]) for p in scores for m in MATERIALS]
    members = mean_over_runs([[record(p, m, "members", scores[p][m]["members"][k]) for p in scores for m in MATERIALS]
                              for k in range(runs)])
    paired = paired_differences(average + members, "average", "eval", exclude=(), metrics=SCORES)["members"]
    out = {}
    for m in MATERIALS:
        out[m] = {}
        for s in SCORES:
            per_run = np.array([[x[s] for x in scores[p][m]["members"]] for p in scores])     # (photos, K)
            out[m][s] = {"members": per_run.mean(axis=0).tolist(),
                         "average": float(np.mean([scores[p][m]["average"][s] for p in scores])),
                         **paired[m][s]}
    return out


def table(summ: dict, runs: list[Path]) -> str:
    names = [r.name for r in runs]
    lines = ["| probe | score | " + " | ".join(names) + " | average | average − members, paired |",
             "|---|---|" + "---:|" * len(names) + "---:|:---:|"]
    for m, by_score in summ.items():
        for s, row in by_score.items():
            lo, hi = row["ci95"]
            lines.append(f"| {m} | {s} | " + " | ".join(f"{v:.2f}" for v in row["members"])
                         + f" | {row['average']:.2f} | {row['mean']:+.2f} [{lo:+.2f}, {hi:+.2f}] "
                           f"{row['wins']}/{row['n']} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", type=Path, nargs="+", help="run-photos folders of the same photos, fitted with other seeds")
    ap.add_argument("--method", default="prior")
    ap.add_argument("--json", type=Path, default=None, help="also write the per-photo scores and the summary")
    args = ap.parse_args(argv)
    if len(args.runs) < 2:
        ap.error("give at least two runs")
    scores = ensemble_scores(args.runs, args.method)
    summ = summary(scores)
    print(f"{len(scores)} photos, method {args.method}, the probes averaged over {len(args.runs)} fits\n")
    print(table(summ, args.runs))
    if args.json:
        args.json.write_text(json.dumps({"photos": scores, "summary": summ}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
