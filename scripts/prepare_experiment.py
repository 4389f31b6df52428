"""How well `roomlight prepare` restores procedural rooms: depth AbsRel and the inpainted caps' error.

Two steps around the command (docs/prepare.md, "Measured"):

    # radiance-only inputs and the true depth beside them, from rooms rendered with a blind spot
    python scripts/prepare_experiment.py strip CAPPED --inputs IN --truth TRUTH
    roomlight prepare IN --out OUT --depth synthetic --truth TRUTH
    # compare with the same rooms rendered without the blind spot
    python scripts/prepare_experiment.py measure OUT --full FULL [--figure PNG]

Depth is scored three ways: as written (the floor put at --camera-height, 1.6 m, whatever the
room's true camera height), at the room's true camera height (what --camera-height with the true
value writes: the depth scales linearly with it), and after aligning each panorama's median to
the truth (the fusion alone). The cap is scored in the original radiance units against the
uncapped render, next to a baseline that stretches the border row down over the cap.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from roomlight.core.color import luminance_np
from roomlight.core.io import read_panorama, write_exr, write_panorama


def strip(capped: Path, inputs: Path, truth: Path) -> None:
    inputs.mkdir(parents=True, exist_ok=True)
    truth.mkdir(parents=True, exist_ok=True)
    files = sorted(capped.glob("*/room-*.exr"))
    for f in files:
        p = read_panorama(f)
        write_panorama(inputs / f.name, p.radiance, metadata=p.metadata)  # radiance only: no Z
        write_exr(truth / f.name, {"Z": p.depth})
    print(f"{len(files)} radiance-only panoramas in {inputs}, their depth in {truth}")


def _cap_scores(pred: np.ndarray, true: np.ndarray, rows: int) -> dict:
    i0 = pred.shape[0] - rows
    yp, yt = luminance_np(pred[i0:]), luminance_np(true[i0:])
    stretch = np.broadcast_to(luminance_np(pred[i0 - 1:i0]), yt.shape)  # the border row pulled down
    ly = np.log(luminance_np(pred))

    def scores(y):
        return {"mean_rel_error": float(abs(y.mean() - yt.mean()) / yt.mean()),
                "pixel_log2_mae": float(np.mean(np.abs(np.log2(y) - np.log2(yt))))}

    return {"inpainted": scores(yp), "stretch_baseline": scores(stretch),
            "seam_step": float(np.abs(ly[i0] - ly[i0 - 1]).mean()),
            "gradient_above": float(np.abs(ly[i0 - 1] - ly[i0 - 2]).mean())}


def measure(prepared: Path, full: Path, figure: Path | None) -> dict:
    truths = {f.name: f for f in full.glob("*/room-*.exr")}
    rows, shown = [], None
    for f in sorted(prepared.glob("*/room-*.exr")):
        p = read_panorama(f)
        t = read_panorama(truths[f.name])
        d, dt = p.depth.astype(np.float64), t.depth.astype(np.float64)
        cam = float(t.metadata["room"]["capture"][1])  # the floor is y = 0
        written_height = p.metadata["prepare"]["depth"]["floor_m"]
        absrel = lambda x: float(np.mean(np.abs(x - dt) / dt))  # noqa: E731
        rad_p = p.radiance.astype(np.float64) * p.metadata["exposure_factor"]
        rad_t = t.radiance.astype(np.float64) * t.metadata["exposure_factor"]
        cap = _cap_scores(rad_p, rad_t, p.metadata["prepare"]["nadir"]["rows"])
        rows.append({"file": f.name, "camera_height": cam,
                     "absrel_written": absrel(d), "absrel_true_height": absrel(d * cam / written_height),
                     "absrel_median_aligned": absrel(d * np.median(dt / d)), **cap})
        if shown is None:
            shown = (p, t, rad_p, rad_t)
    if not rows:
        raise SystemExit(f"no prepared rooms under {prepared}")
    mean = lambda key, sub=None: float(np.mean([r[key] if sub is None else r[key][sub] for r in rows]))  # noqa: E731
    summary = {
        "rooms": len(rows),
        "depth_absrel": {"written_1.6m": mean("absrel_written"), "true_camera_height": mean("absrel_true_height"),
                         "median_aligned": mean("absrel_median_aligned"),
                         "true_camera_height_max": max(r["absrel_true_height"] for r in rows)},
        "cap": {"inpainted_mean_rel_error": mean("inpainted", "mean_rel_error"),
                "inpainted_pixel_log2_mae": mean("inpainted", "pixel_log2_mae"),
                "stretch_mean_rel_error": mean("stretch_baseline", "mean_rel_error"),
                "stretch_pixel_log2_mae": mean("stretch_baseline", "pixel_log2_mae"),
                "seam_step": mean("seam_step"), "gradient_above": mean("gradient_above")},
    }
    (prepared / "experiment.json").write_text(json.dumps({"summary": summary, "rooms": rows}, indent=2))
    if figure is not None:
        _figure(figure, *shown)
    return summary


def _figure(path: Path, p, t, rad_p, rad_t) -> None:
    """Capped input | prepared | truth, radiance above depth, each 2x enlarged."""
    from roomlight.core.io import save_png
    from roomlight.core.io.preview import auto_exposure_stops, colorize_depth, tonemap_gamma

    stops = auto_exposure_stops(rad_t)
    capped = rad_t.copy()
    capped[rad_t.shape[0] - p.metadata["prepare"]["nadir"]["rows"]:] = 0
    lo, hi = float(t.depth.min()), float(t.depth.max())
    tiles = [[tonemap_gamma(x, stops) for x in (capped, rad_p, rad_t)],
             [np.zeros_like(colorize_depth(t.depth)), colorize_depth(p.depth, lo, hi, log=True),
              colorize_depth(t.depth, lo, hi, log=True)]]
    gap = 4
    h, w = tiles[0][0].shape[:2]
    sheet = np.full((2 * h + gap, 3 * w + 2 * gap, 3), 255, np.uint8)
    for r, row in enumerate(tiles):
        for c, tile in enumerate(row):
            sheet[r * (h + gap):r * (h + gap) + h, c * (w + gap):c * (w + gap) + w] = tile
    save_png(path, np.repeat(np.repeat(sheet, 2, axis=0), 2, axis=1))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    s = sub.add_parser("strip", help="radiance-only inputs + true depth files from rendered rooms")
    s.add_argument("capped", type=Path)
    s.add_argument("--inputs", type=Path, required=True)
    s.add_argument("--truth", type=Path, required=True)
    m = sub.add_parser("measure", help="score a prepared folder against uncapped renders")
    m.add_argument("prepared", type=Path)
    m.add_argument("--full", type=Path, required=True)
    m.add_argument("--figure", type=Path, default=None)
    a = ap.parse_args()
    if a.cmd == "strip":
        strip(a.capped, a.inputs, a.truth)
    else:
        print(json.dumps(measure(a.prepared, a.full, a.figure), indent=2))


if __name__ == "__main__":
    main()
