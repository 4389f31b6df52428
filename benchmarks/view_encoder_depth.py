"""What the view encoder makes of a view with and without its depth, on validation rooms: the room's
look, its size and its energy.

Each validation panorama gives one fixed random view, cut and exposed as the encoder's training views are
(docs/photo.md, "The view encoder"). Every encoder given reads it three ways:

- ``true depth``: the view's own depth (what `fit-photo` has: a depth map);
- ``guess``: the depth of `roomlight estimate`'s geometric guess (a floor 1.5 m below, the rest 3.5 m);
- ``withheld``: no depth at all (the depth channel empty; meaningful for a depth-optional encoder).

and the decoded room is scored against the whole panorama: PSNR LDR of the radiance, depth AbsRel over the
whole panorama, the depth error in the directions the view shows (median |ln(D̂ / D)| over its seen cells:
the room's size as the photograph would fix it), the exposure error |s − s*|, and the energy the decoded
room delivers: the mean over 14 surface orientations of log2(Ê / E), the irradiance at the capture point
over the truth's (0: right; −1: half the light; :mod:`roomlight.prior.losses.irradiance`), and the same
after the decoded room is scaled to the truth's log-average on the cells the view shows (what a photo fit's
exposure match does, so the column is the unseen room's energy relative to the seen part). Paired per view
against the first encoder read with the true depth, with 95 % bootstrap intervals. Two rows for scale: the
prior's mean room (z = 0) and the prior's encoder given the *whole* panorama (out of reach from one view).

Run: .venv/bin/python benchmarks/view_encoder_depth.py --data data/rooms64b \
         --encoder bundled=src/roomlight/assets/prior/view_encoder \
         --encoder depth-optional=runs/view-encoder-l512-depth-optional/best [--views 96] [--out FILE.json]
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np
import torch

ROOT = Path(__file__).resolve().parents[1]
METRICS = ("psnr_ldr", "abs_rel", "seen_log_depth_error", "exposure_error", "irradiance_stops",
           "irradiance_seen_stops")


def make_views(rad, dep, prior, n: int, seed: int = 0):
    """n fixed views (one per panorama): (partial with true depth, partial with the guess, s*, seen mask)."""
    from roomlight.core.geometry.lift import lift_view
    from roomlight.fitting.photo.estimate import first_depth_guess
    from roomlight.prior.viewenc.config import ViewTrainConfig
    from roomlight.prior.viewenc.crops import crop_rotation, cut_view, expose, occluder_mask, random_crop_spec

    cfg = ViewTrainConfig()
    rng = np.random.default_rng(10_000 + seed)
    h, w = rad.shape[-2:]
    views = []
    for i in range(min(n, len(rad))):
        r, d = rad[i], dep[i]
        if rng.random() < 0.5:
            r, d = r.flip(-1), d.flip(-1)
        spec = random_crop_spec(rng, w, cfg.fov_deg, cfg.pitch_deg, cfg.roll_deg, cfg.aspect)
        image, points = cut_view(r, d, spec)
        image, a = expose(image, float(rng.uniform(math.log(cfg.exposure_key[0]), math.log(cfg.exposure_key[1]))))
        valid = torch.from_numpy(occluder_mask(rng, spec.height, spec.width, cfg.occluders))
        rot = crop_rotation(spec)
        rays = points / points.norm(dim=-1, keepdim=True)
        guess = first_depth_guess((rays.double().numpy() @ rot.T))
        guessed_points = rays * torch.from_numpy(guess)[..., None].float()
        true_part = lift_view(points, image, rot, (h, w), valid)
        guess_part = lift_view(guessed_points, image, rot, (h, w), valid)
        views.append({"radiance": r, "depth": d, "true": true_part, "guess": guess_part, "a": a})
    return views


def _room_scores(prior, z, v, seen) -> dict:
    """The decoded room of latent z (1, D) against view v's whole panorama (every metric but the exposure)."""
    from roomlight.prior.eval.metrics import abs_rel, psnr, to_ldr
    from roomlight.prior.losses.irradiance import irradiance_log_ratio

    rad_hat, dep_hat = prior.decode(z)
    target_r, target_d = v["radiance"][None], v["depth"][None]
    err = torch.log(dep_hat[0, 0][seen].double() / target_d[0, 0][seen].double()).abs()
    return {"psnr_ldr": float(psnr(to_ldr(rad_hat, target_r), to_ldr(target_r)).clamp(max=100)[0]),
            "abs_rel": float(abs_rel(dep_hat, target_d)[0]),
            "seen_log_depth_error": float(err.median()),
            "irradiance_stops": float(irradiance_log_ratio(rad_hat, target_r)[0]),
            "irradiance_seen_stops": float(irradiance_log_ratio(rad_hat, target_r, seen=seen[None])[0])}


@torch.no_grad()
def score(prior, encoder, views, mode: str) -> list[dict]:
    from roomlight.prior.model.view_encoder import view_input

    out = []
    for v in views:
        part = v["guess"] if mode == "guess" else v["true"]
        x, k = view_input(part, prior.normalization, depth=(mode != "withheld"))
        z, s = encoder(x[None].float())
        exposure_error = abs(float(s[0]) - (v["a"] - math.log(k)))
        out.append({**_room_scores(prior, z, v, part.seen), "exposure_error": exposure_error})
    return out


@torch.no_grad()
def reference_rows(prior, views) -> dict[str, list[dict]]:
    """The mean room (z = 0) and the prior's encoder mean of the whole panorama, scored as the encoders are
    (no exposure: neither reads the view)."""
    zero = torch.zeros(1, prior.config.latent_dim)
    rows: dict[str, list[dict]] = {"z = 0 (the mean room)": [], "the whole panorama, encoded": []}
    for v in views:
        whole = prior.encode(v["radiance"][None], v["depth"][None]).mean
        for name, z in zip(rows, (zero, whole)):
            rows[name].append({**_room_scores(prior, z, v, v["true"].seen), "exposure_error": math.nan})
    return rows


def paired(a: list[float], b: list[float], reps: int = 10000, seed: int = 0):
    d = np.asarray(a) - np.asarray(b)
    rng = np.random.default_rng(seed)
    boots = d[rng.integers(0, len(d), (reps, len(d)))].mean(1)
    return float(d.mean()), float(np.percentile(boots, 2.5)), float(np.percentile(boots, 97.5))


def main(argv=None) -> None:
    from roomlight.prior.model.runs import load_run_model
    from roomlight.prior.model.view_encoder import ViewEncoder
    from roomlight.prior.viewenc.trainer import load_panoramas

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, required=True, help="a panorama folder with a val/ split (roomlight synth)")
    ap.add_argument("--model", type=Path, default=ROOT / "src" / "roomlight" / "assets" / "prior")
    ap.add_argument("--encoder", action="append", required=True, metavar="NAME=DIR", help="a view encoder folder")
    ap.add_argument("--views", type=int, default=96)
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args(argv)
    prior = load_run_model(args.model, device="cpu")
    rad, dep, _ = load_panoramas(args.data, "val", prior.config.resolution, limit=args.views,
                                 note=lambda m: print(m, file=sys.stderr))
    views = make_views(rad, dep, prior, args.views)
    rows: dict[str, list[dict]] = {}
    for spec in args.encoder:
        name, folder = spec.split("=", 1)
        enc = ViewEncoder.from_pretrained(folder, prior.config).eval()
        modes = {"true depth": "true", "guess": "guess", "withheld": "withheld"}  # row label -> score()'s mode
        if not enc.reads_without_depth:
            del modes["withheld"]
        for label, mode in modes.items():
            rows[f"{name}, {label}"] = score(prior, enc, views, mode)
    base = next(iter(rows))
    rows.update(reference_rows(prior, views))
    print(f"{len(views)} validation views of {args.data}; mean over views, and paired against `{base}` "
          "(mean difference [95 % bootstrap interval])\n")
    print("| encoder, depth | PSNR LDR ↑ | depth AbsRel ↓ | depth error where seen, median abs ln ↓ "
          "| exposure error ↓ | irradiance, log2 ratio (0 best) | the same, seen part matched (0 best) |")
    print("|---|:---:|:---:|:---:|:---:|:---:|:---:|")
    for name, rs in rows.items():
        cells = []
        for m in METRICS:
            vals = [r[m] for r in rs]
            if any(math.isnan(x) for x in vals):
                cells.append("–")
                continue
            cell = f"{np.mean(vals):.3f}" if m != "psnr_ldr" else f"{np.mean(vals):.2f}"
            if name != base:
                d, lo, hi = paired(vals, [r[m] for r in rows[base]])
                cell += f" ({d:+.3f} [{lo:+.3f}, {hi:+.3f}])"
            cells.append(cell)
        print(f"| {name} | " + " | ".join(cells) + " |")
    if args.out:
        args.out.write_text(json.dumps(rows))


if __name__ == "__main__":
    main()
