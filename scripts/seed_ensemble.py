"""Is a photo fit's error the seed's or the photograph's? The light that averages several fits, scored.

Two or more `roomlight bench run-photos` runs of the same photos and method that differ only in the fit's
seed (`--set seed=N`) give several lights per photo. Their mean (each fitted light at 1/K of its radiance,
all together) is a light too, and a probe render is linear in the light's radiance (the probes and the
photo's objects do not emit), so the mean light's probe render is the mean of the members' renders:
nothing is rendered again. If the members' errors were independent draws around the truth, the mean
light would score clearly better than its members (the spread shrinks as 1/K); if the mean scores as its
members do, the error is shared: it is what the photograph and the objective give, not the seed.

The averaged render also holds K times the members' samples, which favours the mean light a little: its
gain over the members is an upper bound on what averaging the fits buys.

Prints, per probe material, each run's mean PSNR LDR and angular error, the mean light's, and the paired
difference mean light − mean of its members per photo (mean, 95 % bootstrap interval, photos won).

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


def _read_rgb(path: Path) -> np.ndarray:
    from roomlight.core.io import read_exr

    channels = read_exr(path)
    return np.stack([channels[c] for c in "RGB"], axis=-1)


def ensemble_scores(runs: list[Path], method: str) -> dict:
    """``{photo: {material: {"members": [{score: value}], "mean_light": {score: value}}}}`` over the photos
    every run finished; the mean light's render is the members' renders averaged."""
    from roomlight.evaluation.harness.metrics import score_view
    from roomlight.evaluation.photobench.scoring import load_truth

    def finished(run: Path) -> set[str]:
        cases = run / "cases"
        if not cases.is_dir():
            raise SystemExit(f"{run}: not a run-photos folder (no cases/)")
        return {d.name for d in cases.iterdir() if (d / method / "result.json").is_file()}

    photos = sorted(set.intersection(*(finished(r) for r in runs)))
    if not photos:
        raise SystemExit(f"no photo has a finished {method!r} case in every run")
    out = {}
    for photo in photos:
        folders = [r / "cases" / photo / method for r in runs]
        record = json.loads((folders[0] / "result.json").read_text())
        truth = load_truth(record["case_dir"])
        mask = truth.window_mask > 0
        out[photo] = {}
        for m in MATERIALS:
            renders = [_read_rgb(f / f"probes_{m}.exr") for f in folders]
            gt = truth.probe_images[m]
            members = [score_view(r, gt, mask) for r in renders]
            mean_light = score_view(np.mean(renders, axis=0), gt, mask)
            out[photo][m] = {"members": [{s: float(x[s]) for s in SCORES} for x in members],
                             "mean_light": {s: float(mean_light[s]) for s in SCORES}}
    return out


def summary(scores: dict) -> dict:
    """Per material and score: each member run's mean, the mean light's, and the paired difference
    mean light − mean of the members over photos (``mean``, ``ci95``, ``wins``, ``n``)."""
    from roomlight.core.stats import bootstrap_mean_interval

    out = {}
    for m in MATERIALS:
        out[m] = {}
        for s in SCORES:
            members = np.array([[x[s] for x in scores[p][m]["members"]] for p in scores])   # (photos, K)
            mean_light = np.array([scores[p][m]["mean_light"][s] for p in scores])
            diff = mean_light - members.mean(axis=1)
            good = diff > 0 if s == "psnr_ldr" else diff < 0
            out[m][s] = {"members": members.mean(axis=0).tolist(), "mean_light": float(mean_light.mean()),
                         "mean": float(diff.mean()), "ci95": list(bootstrap_mean_interval(diff)),
                         "wins": int(good.sum()), "n": int(diff.size)}
    return out


def table(summ: dict, runs: list[Path]) -> str:
    names = [r.name for r in runs]
    lines = ["| probe | score | " + " | ".join(names) + " | mean light | mean light − members, paired |",
             "|---|---|" + "---:|" * len(names) + "---:|:---:|"]
    for m, by_score in summ.items():
        for s, row in by_score.items():
            lo, hi = row["ci95"]
            lines.append(f"| {m} | {s} | " + " | ".join(f"{v:.2f}" for v in row["members"])
                         + f" | {row['mean_light']:.2f} | {row['mean']:+.2f} [{lo:+.2f}, {hi:+.2f}] "
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
    print(f"{len(scores)} photos, method {args.method}, the light averaged over {len(args.runs)} fits\n")
    print(table(summ, args.runs))
    if args.json:
        args.json.write_text(json.dumps({"photos": scores, "summary": summ}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
