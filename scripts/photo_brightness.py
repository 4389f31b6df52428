"""How much of a photo benchmark run's probe error is the recovered light's overall brightness.

For every photo and method, the light is rescaled by the one factor that gives its diffuse probes the
true mean radiance (an *exposure oracle*), and the probes are scored again. A probe render is linear in
the light's radiance (the scene's objects do not emit), so the rescaled render is exact: nothing is
rendered again. Prints per method the recovered/true brightness (geometric mean and median over photos,
the mean |log2| error in stops, and how many photos are too dark) and the PSNR LDR per probe material as
fitted and at the true brightness. With ``--against OTHER`` (a run of the same photos), also how the
level moved from OTHER to RESULTS: the mean shift of log2 brightness over the photos both hold, and the
correlation of their per-photo log2 levels (near 1: each photo's level is set by the same thing in both).

Run: .venv/bin/python scripts/photo_brightness.py RESULTS [--methods prior,prior-envmap,...] [--json FILE]
         [--against OTHER]
     (RESULTS: a `roomlight bench run-photos` folder whose cases still hold their probe renders)
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

MATERIALS = ("diffuse", "matte", "mirror")


def _read_rgb(path: Path) -> np.ndarray:
    from roomlight.core.io import read_exr

    channels = read_exr(path)
    return np.stack([channels[c] for c in "RGB"], axis=-1)


def brightness_table(results: Path, methods: list[str]) -> dict:
    """{method: {"ratio": [recovered/true per photo], "fitted": {material: [psnr]}, "rescaled": {...}}}."""
    from roomlight.evaluation.harness.metrics import score_view
    from roomlight.evaluation.photobench.scoring import load_truth

    out = {m: {"photos": [], "ratio": [], "fitted": {k: [] for k in MATERIALS},
               "rescaled": {k: [] for k in MATERIALS}} for m in methods}
    if not (results / "cases").is_dir():
        sys.exit(f"error: {results}: not a `roomlight bench run-photos` folder (it has no cases/)")
    cases = sorted(p for p in (results / "cases").iterdir() if p.is_dir())
    if not cases:
        sys.exit(f"error: {results}: no cases (run `roomlight bench run-photos` first)")
    for case in cases:
        for m in methods:
            folder = case / m
            if not (folder / "result.json").is_file():
                continue
            record = json.loads((folder / "result.json").read_text())
            renders = {k: folder / f"probes_{k}.exr" for k in MATERIALS}
            if not all(p.is_file() for p in renders.values()):
                sys.exit(f"error: {folder}: the probe renders are missing (a results copy without images?)")
            truth = load_truth(record["case_dir"])
            inside = truth.window_mask > 0
            images = {k: _read_rgb(p) for k, p in renders.items()}
            scale = float(truth.probe_images["diffuse"][inside].mean()) / max(float(images["diffuse"][inside].mean()), 1e-12)
            out[m]["photos"].append(case.name)
            out[m]["ratio"].append(1.0 / scale)
            for k, image in images.items():
                out[m]["fitted"][k].append(score_view(image, truth.probe_images[k], inside)["psnr_ldr"])
                out[m]["rescaled"][k].append(score_view(image * scale, truth.probe_images[k], inside)["psnr_ldr"])
    return out


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("results", type=Path)
    ap.add_argument("--methods", default="prior,prior-envmap,prior-samples,direct-envmap,prior-ceiling,oracle,oracle-envmap")
    ap.add_argument("--json", type=Path, help="also write the per-photo values here")
    ap.add_argument("--against", type=Path, help="another run of the same photos: how the level moved from it")
    args = ap.parse_args(argv)
    methods = [m for m in args.methods.split(",") if m]
    table = brightness_table(args.results, methods)
    print("| method | recovered / true brightness: geometric mean, median | level error, mean abs log2 (stops) "
          "| photos too dark | PSNR LDR as fitted (diffuse / matte / mirror) | at the true brightness |")
    print("|---|:---:|:---:|:---:|:---:|:---:|")
    for m, o in table.items():
        if not o["ratio"]:
            continue
        r = np.log2(o["ratio"])
        fitted = " / ".join(f"{np.mean(o['fitted'][k]):.2f}" for k in MATERIALS)
        rescaled = " / ".join(f"{np.mean(o['rescaled'][k]):.2f}" for k in MATERIALS)
        print(f"| {m} | {2 ** r.mean():.2f}, {2 ** np.median(r):.2f} | {np.abs(r).mean():.2f} "
              f"| {int((r < 0).sum())}/{len(r)} | {fitted} | {rescaled} |")
    if args.against:
        other = brightness_table(args.against, methods)
        print(f"\nLevel moved from {args.against} to {args.results} (log2 brightness, photos both hold):\n")
        print("| method | photos | mean shift (stops) | correlation of per-photo levels |")
        print("|---|:---:|:---:|:---:|")
        for m in methods:
            mine = dict(zip(table[m]["photos"], np.log2(table[m]["ratio"])))
            theirs = dict(zip(other[m]["photos"], np.log2(other[m]["ratio"])))
            common = sorted(set(mine) & set(theirs))
            if len(common) < 2:
                continue
            a, b = np.array([mine[c] for c in common]), np.array([theirs[c] for c in common])
            print(f"| {m} | {len(common)} | {(a - b).mean():+.2f} | {np.corrcoef(a, b)[0, 1]:.2f} |")
    if args.json:
        args.json.write_text(json.dumps(table, indent=1))


if __name__ == "__main__":
    main()
