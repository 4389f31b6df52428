"""Is the fitted light's fault its level, its contrast, its sharpness, or none? Re-render its probes under each change.

A photo benchmark run keeps each fitted light (``recovered.exr``). This script changes the light in ways
that need no new fit and scores the probes again (the benchmark's renders and scores, 64 spp):

- **contrast** (``--gammas``): every texel's luminance ``Y`` becomes ``Y ** gamma`` (colour kept: the RGB
  triple is scaled by ``Y ** (gamma - 1)``). ``gamma < 1`` lifts the dim walls against the lamps,
  ``gamma > 1`` the reverse;
- **blur** (``--blurs``, degrees): the radiance blurred by a Gaussian of that angular standard deviation,
  a stand-in for the mean over the layouts the unseen room might have (the depth is kept);
- **level**: the re-rendered probes are scaled (a probe render is linear in the light) either back to the
  diffuse probes' mean of the light as fitted (``level kept``: only the contrast changed) or to the true
  diffuse probes' mean (``true level``: the exposure oracle of ``scripts/photo_brightness.py``).

Per run and change it prints the PSNR LDR of the diffuse, matte and mirror probes and, paired per photo
against the light as fitted, the mean difference with its bootstrap interval. If the mirror probes gain
from neither change, what they lack is where the unseen room's light is, not how bright or how contrasty.

Run: .venv/bin/python scripts/light_contrast.py RUN [RUN ...] [--method prior] [--gammas 0.85,1.15,1.3]
         [--blurs 5,10,20] [--json FILE]
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


def blurred(radiance: np.ndarray, degrees: float, chunk: int = 1024) -> np.ndarray:
    """(H, 2H, 3) equirectangular radiance blurred by a Gaussian of ``degrees`` angular standard deviation.

    Exact on the sphere, by brute force: every output texel is the average of all input texels weighted by
    exp(-theta^2 / (2 sigma^2)) (theta the angle between the two texels' directions) times the input texel's
    solid angle. A constant map stays constant, and since the kernel depends on the angle alone, the
    solid-angle-weighted energy is kept to the map's discretisation (tested at the equator and the poles).
    O((H W)^2): about a second at 64 x 128. Zero ``degrees`` returns the input.
    """
    from roomlight.core.geometry.equirect import pixel_directions, pixel_solid_angles

    rad = np.asarray(radiance, np.float64)
    if degrees <= 0:
        return rad.astype(np.float32)
    h, w, _ = rad.shape
    dirs = pixel_directions(h, w).double().numpy().reshape(-1, 3)
    area = pixel_solid_angles(h, w).double().numpy().reshape(-1)
    flat = rad.reshape(-1, 3)
    two_sigma2 = 2.0 * np.deg2rad(degrees) ** 2
    out = np.empty_like(flat)
    for start in range(0, len(dirs), chunk):
        angle = np.arccos(np.clip(dirs[start:start + chunk] @ dirs.T, -1.0, 1.0))     # (chunk, H W)
        weight = np.exp(-angle ** 2 / two_sigma2) * area[None, :]
        out[start:start + chunk] = (weight @ flat) / weight.sum(axis=1, keepdims=True)
    return out.reshape(h, w, 3).astype(np.float32)


def changes(gammas: list[float], blurs: list[float]) -> dict:
    """``{label: function of the radiance}``, the light as fitted (``as fitted``) first."""
    out = {"as fitted": lambda rad: np.asarray(rad, np.float32)}
    out.update({f"gamma {g:g}": (lambda rad, g=g: contrast_changed(rad, g)) for g in gammas if g != 1.0})
    out.update({f"blur {d:g}°": (lambda rad, d=d: blurred(rad, d)) for d in blurs if d > 0})
    return out


def case_scores(folder: Path, variants: dict, spp: int = 64, given_depth: bool = True) -> dict:
    """``{label: {level: {material: psnr_ldr}}}`` for one fitted case folder (``cases/ID/METHOD``), one entry
    per change of :func:`changes` (the first: the light as fitted). ``spp`` and ``given_depth`` as the run
    scored its probes (:func:`~roomlight.evaluation.photobench.scoring.render_probes`)."""
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
    for label, change in variants.items():
        light = Light(change(pano.radiance), pano.depth, kind, frame)
        renders: dict = {}
        score_light(truth, light, spp, renders=renders, given_depth=given_depth)
        mean = max(float(renders["diffuse"][inside].mean()), 1e-12)
        fitted_mean = mean if fitted_mean is None else fitted_mean
        out[label] = {level: {m: score_view(renders[m] * target / mean, truth.probe_images[m], inside)["psnr_ldr"]
                              for m in MATERIALS}
                      for level, target in zip(LEVELS, (fitted_mean, true_mean))}
    return out


def _numbers(text: str, option: str) -> list[float]:
    try:
        values = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        sys.exit(f"error: {option} {text!r}: give numbers separated by commas")
    if not all(np.isfinite(v) and v >= 0 for v in values):
        sys.exit(f"error: {option} {text!r}: every number must be finite and not negative")
    return values


def _run_spp(run: Path) -> int:
    """The probe samples per pixel ``run`` scored with (its run.json; the benchmark's default without one)."""
    from roomlight.evaluation.photobench.runner import DEFAULT_EVAL_SPP

    record = json.loads((run / "run.json").read_text()) if (run / "run.json").is_file() else {}
    return int(record.get("eval_spp", DEFAULT_EVAL_SPP))


def _case_scores_or_exit(folder: Path, variants: dict, spp: int, given_depth: bool) -> dict:
    from roomlight.errors import RoomlightError

    try:
        return case_scores(folder, variants, spp, given_depth)
    except (RoomlightError, OSError, KeyError, ValueError) as e:
        sys.exit(f"error: {folder}: {e} (has the photo case moved since the run?)")


def main(argv=None) -> None:
    from roomlight.core.stats import bootstrap_mean_interval
    from roomlight.evaluation.photobench.adapter import PHOTO_FIT_METHODS

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+", type=Path)
    ap.add_argument("--method", default="prior")
    ap.add_argument("--gammas", default="0.85,1.15,1.3", help="luminance exponents (1: the light as fitted)")
    ap.add_argument("--blurs", default="", help="blur widths, degrees (angular standard deviation)")
    ap.add_argument("--json", type=Path, help="also write the per-photo scores here")
    args = ap.parse_args(argv)
    gammas = _numbers(args.gammas, "--gammas")
    if 0.0 in gammas:
        sys.exit("error: --gammas: every exponent must be positive")
    variants = changes(gammas, _numbers(args.blurs, "--blurs"))
    everything = {}
    for run in args.runs:
        cases = sorted(p / args.method for p in (run / "cases").glob("*") if (p / args.method / "recovered.exr").is_file())
        if not cases:
            sys.exit(f"error: {run}: no case with {args.method}/recovered.exr (a `bench run-photos` folder?)")
        # fitted through fit-photo, the probes stand where the photo's given depth puts them (as the run scored)
        given_depth = args.method in PHOTO_FIT_METHODS
        per_photo = {c.parent.name: _case_scores_or_exit(c, variants, _run_spp(run), given_depth) for c in cases}
        everything[str(run)] = per_photo
        print(f"\n{run} ({len(per_photo)} photos), PSNR LDR diffuse / matte / mirror; paired against the light as fitted")
        print("| change | level | probes | diffuse | matte | mirror |")
        print("|---|---|:---:|:---:|:---:|:---:|")
        base = np.array([[s["as fitted"][LEVELS[0]][m] for m in MATERIALS] for s in per_photo.values()])
        for label in variants:
            for level in LEVELS:
                values = np.array([[s[label][level][m] for m in MATERIALS] for s in per_photo.values()])
                cells = []
                for j in range(len(MATERIALS)):
                    d = values[:, j] - base[:, j]
                    lo, hi = bootstrap_mean_interval(d)
                    same = np.allclose(d, 0.0, atol=1e-6)   # the light as fitted, rescaled to its own level
                    cells.append("—" if same else f"{d.mean():+.2f} [{lo:+.2f}, {hi:+.2f}]")
                print(f"| {label} | {level} | {' / '.join(f'{v:.2f}' for v in values.mean(0))} | " + " | ".join(cells) + " |")
    if args.json:
        args.json.write_text(json.dumps(everything, indent=1, ensure_ascii=False))


if __name__ == "__main__":
    main()
