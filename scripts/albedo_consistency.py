"""Does the seen room reflect like the light's own unseen room? A diagnosis of the light's level.

A 2.5D light is a room: its texels that are not lamps are walls, lit by the rest of it. Their apparent
albedo pi L / E (E: the irradiance the whole light delivers to each texel) does not change when the light
is scaled, while the apparent albedo of the photograph's visible room (its pixels are fixed) falls as
the light brightens. If the walls the camera sees reflect like the walls it does not see (the same paint,
the same kind of room), the ratio of the two medians says by how much the light's level is off:

    predicted factor c = median rho_seen / median rho_unseen     (1: consistent)

This script measures, on a photo benchmark run's cases, how far that assumption holds under the true
light (the case's oracle panorama as a 2.5D light) and whether, under each fitted light, c predicts the
level error the probes show (recovered / true mean radiance of the diffuse probes). Nothing is fitted.

It also asks a weaker question: does the seen room at least *bracket* the level? Scaling the light by k
divides every visible point's apparent albedo by k, so the factors k that keep the central share of them
(all but ``--bracket-trim`` at each end) inside the albedos real surfaces span, [0.03, 0.9], are

    q_hi / 0.9  <=  k  <=  q_lo / 0.03        (q_lo, q_hi: the trimmed low and high quantiles)

(``fit-photo`` reports this bracket as ``level_bracket``.) Under the true light the bracket should hold
k = 1; under a fitted light, the factor the probes need (true / recovered). An empty bracket
(q_hi / 0.9 > q_lo / 0.03) says no single level fits the seen room.

Run: .venv/bin/python scripts/albedo_consistency.py RESULTS [RESULTS ...] [--method prior] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))


def _seen_in_camera(points_light: np.ndarray, light_from_camera: np.ndarray, camera) -> np.ndarray:
    """(T,) bool: whether each light-frame point falls inside the photograph's frame (in front of it).

    ``camera``: the photograph's own :class:`~roomlight.fitting.photo.camera.PhotoCamera` (its pose the
    identity, so its "world" is the camera frame)."""
    cam = np.linalg.inv(light_from_camera)
    xy, z = camera.project(points_light @ cam[:3, :3].T + cam[:3, 3])
    return (z > 0) & (xy[:, 0] >= 0) & (xy[:, 0] <= camera.width) & (xy[:, 1] >= 0) & (xy[:, 1] <= camera.height)


def apparent_albedos(light, surface_cam, intrinsics, trim: float = 0.1) -> dict:
    """Median apparent albedo of the visible room and of the light's unseen texels under ``light``.

    Args:
        light: a 2.5D :class:`~roomlight.core.light.Light` (its frame: camera -> light).
        surface_cam: (points, normals, radiance) of the visible room in the camera frame (N, 3) each.
        intrinsics: the photograph's camera at the surface's resolution.
    Returns:
        {"seen": median over the visible points, "unseen": median over the unseen texels, "texels": count,
        "bracket": [k_min, k_max] the level factors the visible room allows, trimmed ``trim`` at each end
        (:func:`roomlight.fitting.photo.room_albedo.level_bracket`, as ``fit-photo`` reports it)}.
    """
    from roomlight.fitting.photo.geometry import SceneTransform
    from roomlight.fitting.photo.room_albedo import (POOLED_HEIGHT, RoomSurface, apparent_albedo, irradiance,
                                                       level_bracket, lifted, pool_emitter, texel_patches)

    frame = np.asarray(light.frame, np.float64)
    to_light = SceneTransform.from_matrix(frame)
    pts, nrm, rad = surface_cam
    surface = RoomSurface(to_light.points(pts), to_light.directions(nrm), rad)
    seen = apparent_albedo(light.radiance, light.depth, surface).numpy()

    rad_p, dep_p = pool_emitter(light.radiance, light.depth, POOLED_HEIGHT)
    pos, n, _ = texel_patches(dep_p)
    # Each texel as a receiver, lifted into the room (off its own patch) as the visible points are.
    e = irradiance(light.radiance, light.depth, lifted(pos, n), n).mean(-1)
    texel_albedo = (math.pi * rad_p.reshape(-1, 3).mean(-1) / e.clamp_min(1e-9)).numpy()
    unseen = ~_seen_in_camera(pos.numpy().astype(np.float64), frame, intrinsics)
    bracket = level_bracket(light.radiance, light.depth, surface, trim=trim)
    return {"seen": float(np.median(seen)), "unseen": float(np.median(texel_albedo[unseen])),
            "texels": int(unseen.sum()),
            "bracket": [bracket["low"], bracket["high"]] if bracket else [float("nan"), float("nan")]}


def visible_room(case_dir: Path):
    """The photograph's unsaturated background points with reliable normals, camera frame (the geometry of
    the ``fast`` preset, the benchmark runs' own)."""
    from roomlight.fitting.photo.case import load_photo
    from roomlight.fitting.photo.config import photo_config
    from roomlight.fitting.photo.geometry import build_geometry
    from roomlight.fitting.photo.room_albedo import lifted

    config = photo_config("fast")
    case = load_photo(str(case_dir), min_object_fraction=config.min_object_fraction)
    geometry = build_geometry(case, config)
    f = geometry.frustum
    keep = f.normal_ok & (f.radiance.max(-1) < config.tau)
    return (lifted(f.points[keep], f.normals[keep]), f.normals[keep], f.radiance[keep]), geometry.intrinsics


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("results", nargs="+", type=Path, help="`roomlight bench run-photos` folders")
    ap.add_argument("--method", default="prior", help="the fitted method whose lights are read (default prior)")
    ap.add_argument("--json", type=Path, help="also write the per-photo rows here")
    ap.add_argument("--bracket-trim", type=float, default=0.1,
                    help="share of the visible points left out at each end of the level bracket (default 0.1, "
                         "fit-photo's level_bracket_trim)")
    args = ap.parse_args(argv)

    from roomlight.core.io import read_panorama
    from roomlight.core.light import Light
    from roomlight.evaluation.photobench.scoring import oracle_light
    from photo_brightness import brightness_table

    rows = []
    for results in args.results:
        table = brightness_table(results, [args.method])[args.method]
        for photo, ratio in zip(table["photos"], table["ratio"]):
            folder = results / "cases" / photo / args.method
            record = json.loads((folder / "result.json").read_text())
            case_dir = Path(record["case_dir"])
            surface, intrinsics = visible_room(case_dir)
            pano = read_panorama(folder / "recovered.exr")
            fitted = Light(pano.radiance, pano.depth, "mesh", pano.metadata["light_from_camera"])
            truth = apparent_albedos(oracle_light(case_dir, "mesh"), surface, intrinsics, args.bracket_trim)
            fit = apparent_albedos(fitted, surface, intrinsics, args.bracket_trim)
            rows.append({"set": results.name, "photo": photo, "level": float(ratio), "truth": truth, "fit": fit})

    w = max([len(r["set"]) for r in rows] + [20]) + 2
    print(f"{'set':<{w}}{'photo':<13}{'level':>7}{'true seen':>11}{'unseen':>8}{'log2 c':>8}"
          f"{'fit seen':>10}{'unseen':>8}{'log2 c':>8}{'corrected':>11}")
    err0, err1, pred, actual, true_c = [], [], [], [], []
    for r in rows:
        ct = math.log2(r["truth"]["seen"] / r["truth"]["unseen"])
        cf = math.log2(r["fit"]["seen"] / r["fit"]["unseen"])
        lv = math.log2(r["level"])
        err0.append(abs(lv))
        err1.append(abs(lv + cf))
        pred.append(cf)
        actual.append(-lv)
        true_c.append(ct)
        print(f"{r['set']:<{w}}{r['photo']:<13}{r['level']:7.2f}{r['truth']['seen']:11.3f}{r['truth']['unseen']:8.3f}"
              f"{ct:+8.2f}{r['fit']['seen']:10.3f}{r['fit']['unseen']:8.3f}{cf:+8.2f}{2 ** (lv + cf):11.2f}")
    print()
    err0, err1, pred, actual, true_c = map(np.array, (err0, err1, pred, actual, true_c))
    sets = [r["set"] for r in rows]
    for name in [*dict.fromkeys(sets), None]:
        k = [i for i, x in enumerate(sets) if name is None or x == name]
        tc = true_c[k]
        corr = float(np.corrcoef(pred[k], actual[k])[0, 1]) if len(k) > 2 else float("nan")
        print(f"{name or 'all':<{w}}{len(k)} photos: under the true light log2 c mean {tc.mean():+.2f} "
              f"(range {tc.min():+.2f} .. {tc.max():+.2f}, std {tc.std():.2f}); the fits' level error mean |log2| "
              f"{err0[k].mean():.2f} stops, after the predicted correction {err1[k].mean():.2f}; "
              f"correlation of predicted and needed corrections {corr:+.2f}")
    print(f"\nLevel bracket from the visible room (trimmed {args.bracket_trim:.0%} at each end), k = the factor on "
          f"the light:\n")
    print(f"{'set':<{w}}{'photo':<13}{'true: k range':>16}{'holds 1':>9}{'fit: k range':>16}{'needed k':>10}"
          f"{'inside':>8}{'width (stops)':>15}")
    held_true, held_fit, empty, widths = [], [], 0, []
    for r in rows:
        t0, t1 = r["truth"]["bracket"]
        f0, f1 = r["fit"]["bracket"]
        need = 1.0 / r["level"]
        held_true.append(t0 <= 1.0 <= t1)
        held_fit.append(f0 <= need <= f1)
        usable = 0 < f0 <= f1          # False for an empty range, one collapsed to 0, or none (nan)
        empty += not usable
        if usable:
            widths.append(math.log2(f1 / f0))
        print(f"{r['set']:<{w}}{r['photo']:<13}{f'{t0:.2f} .. {t1:.2f}':>16}{'yes' if held_true[-1] else 'no':>9}"
              f"{f'{f0:.2f} .. {f1:.2f}':>16}{need:10.2f}{'yes' if held_fit[-1] else 'no':>8}"
              f"{(f'{math.log2(f1 / f0):.2f}' if usable else 'empty'):>15}")
    n = len(rows)
    print(f"\nunder the true light the bracket holds k = 1 on {sum(held_true)}/{n} photos; under the fitted light it "
          f"holds the needed factor on {sum(held_fit)}/{n}, is empty (or none) on {empty}/{n}; median width "
          f"{(float(np.median(widths)) if widths else float('nan')):.2f} stops")
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
