"""Is the fitted light's fault its level, its contrast, or neither? Re-render its probes under both changes.

A photo benchmark run keeps each fitted light (``recovered.exr``). This script changes the light in two
ways that need no new fit and scores the probes again (the benchmark's renders and scores, 64 spp):

- **contrast**: every texel's luminance ``Y`` becomes ``Y ** gamma`` (colour kept: the RGB triple is scaled
  by ``Y ** (gamma - 1)``). ``gamma < 1`` lifts the dim walls against the lamps, ``gamma > 1`` the reverse;
- **level**: the re-rendered probes are scaled (a probe render is linear in the light) either back to the
  diffuse probes' mean of the light as fitted (``level kept``: only the contrast changed) or to the true
  diffuse probes' mean (``true level``: the exposure oracle of ``scripts/photo_brightness.py``).

Per run and gamma it prints the PSNR LDR of the diffuse, matte and mirror probes and, paired per photo
against the light as fitted, the mean difference with its bootstrap interval. If the mirror probes gain
from neither change, what they lack is where the unseen room's light is, not how bright or how contrasty.

Run: .venv/bin/python scripts/light_contrast.py RUN [RUN ...] [--method prior] [--gammas 1,0.85,1.15]
         [--json FILE]
     (RUN: a `roomlight bench run-photos` folder whose cases still hold recovered.exr)
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

MATERIALS = ("diffuse", "matte", "mirror")
LEVELS = ("level kept", "true level")


def contrast_changed(radiance: np.ndarray, gamma: float) -> np.ndarray:
    """(H, W, 3) radiance with its luminance raised to ``gamma``, chromaticity kept; black stays black."""
    from roomlight.core.color import luminance_np

    rad = np.asarray(radiance, np.float64)
    y = luminance_np(rad)
    gain = np.zeros_like(y)
    lit = y > 0
    gain[lit] = y[lit] ** (gamma - 1.0)
    return (rad * gain[..., None]).astype(np.float32)


def case_scores(folder: Path, gammas: list[float], spp: int = 64) -> dict:
    """``{gamma: {level: {material: psnr_ldr}}}`` for one fitted case folder (``cases/ID/METHOD``)."""
    from roomlight.core.io import read_panorama
    from roomlight.core.light import Light
    from roomlight.evaluation.harness.metrics import score_view
    from roomlight.evaluation.photobench.scoring import load_truth, score_light

    record = json.loads((folder / "result.json").read_text())
    truth = load_truth(record["case_dir"])
    inside = truth.window_mask > 0
    pano = read_panorama(folder / "recovered.exr")
    kind, frame = pano.metadata["emitter_kind"], np.asarray(pano.metadata["light_from_camera"])
    true_mean = float(truth.probe_images["diffuse"][inside].mean())
    fitted_mean = None
    out = {}
    for gamma in [1.0] + [g for g in gammas if g != 1.0]:
        light = Light(contrast_changed(pano.radiance, gamma), pano.depth, kind, frame)
        renders: dict = {}
        score_light(truth, light, spp, renders=renders, given_depth=True)
        mean = max(float(renders["diffuse"][inside].mean()), 1e-12)
        fitted_mean = mean if gamma == 1.0 else fitted_mean
        out[gamma] = {level: {m: score_view(renders[m] * target / mean, truth.probe_images[m], inside)["psnr_ldr"]
                              for m in MATERIALS}
                      for level, target in zip(LEVELS, (fitted_mean, true_mean))}
    return out


def main(argv=None) -> None:
    from roomlight.core.stats import bootstrap_mean_interval

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+", type=Path)
    ap.add_argument("--method", default="prior")
    ap.add_argument("--gammas", default="1,0.85,1.15,1.3", help="luminance exponents (1: the light as fitted)")
    ap.add_argument("--json", type=Path, help="also write the per-photo scores here")
    args = ap.parse_args(argv)
    try:
        gammas = sorted({1.0, *(float(g) for g in args.gammas.split(",") if g)})
    except ValueError:
        sys.exit(f"error: --gammas {args.gammas!r}: give numbers separated by commas")
    if any(g <= 0 for g in gammas):
        sys.exit("error: --gammas: every exponent must be positive")
    everything = {}
    for run in args.runs:
        cases = sorted(p / args.method for p in (run / "cases").glob("*") if (p / args.method / "recovered.exr").is_file())
        if not cases:
            sys.exit(f"error: {run}: no case with {args.method}/recovered.exr (a `bench run-photos` folder?)")
        per_photo = {c.parent.name: case_scores(c, gammas) for c in cases}
        everything[str(run)] = {p: {str(g): v for g, v in s.items()} for p, s in per_photo.items()}
        print(f"\n{run} ({len(per_photo)} photos), PSNR LDR diffuse / matte / mirror; paired against the light as fitted")
        print("| gamma | level | probes | diffuse | matte | mirror |")
        print("|:---:|---|:---:|:---:|:---:|:---:|")
        for gamma in gammas:
            for level in LEVELS:
                values = np.array([[s[gamma][level][m] for m in MATERIALS] for s in per_photo.values()])
                base = np.array([[s[1.0][LEVELS[0]][m] for m in MATERIALS] for s in per_photo.values()])
                cells = []
                for j in range(len(MATERIALS)):
                    d = values[:, j] - base[:, j]
                    lo, hi = bootstrap_mean_interval(d)
                    cells.append("—" if not d.any() else f"{d.mean():+.2f} [{lo:+.2f}, {hi:+.2f}]")
                print(f"| {gamma:g} | {level} | {' / '.join(f'{v:.2f}' for v in values.mean(0))} | " + " | ".join(cells) + " |")
    if args.json:
        args.json.write_text(json.dumps(everything, indent=1))


if __name__ == "__main__":
    main()
