"""How far the fitted 2.5D light's seen part lies from the surfaces the photograph shows.

Where the photograph sees the room, the room is the light: a 2.5D light's depth there should be the
distance of those surfaces. For every fitted case of a photo benchmark run this script carries each
background pixel of the photograph (objects and their one-pixel border left out) into the light's frame
(the fit's ``light_from_camera``, in ``recovered.exr``), gathers the pixels by the light's texel their
direction falls in, and compares the light's depth in each such texel with the geometric mean distance of
its pixels. Per photo it prints the median and the mean absolute log2 ratio (fitted / photographed; +0.16
is 12 % behind the surfaces) over those texels, and per run the median over photos. With ``--floor`` also
the share of those texels whose depth is the fit's containment floor (within 1 %), the floor rebuilt from
the run's settings (its ``run.json``: preset and ``--set`` values) by the photo fit's own functions.

Run: .venv/bin/python scripts/seen_depth.py RUN [RUN ...] [--method prior] [--floor]
     (RUN: a `roomlight bench run-photos` folder whose cases still hold recovered.exr)
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np


def seen_texels(points: np.ndarray, resolution: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """The texels that light-frame ``points`` (N, 3) fall in and the geometric mean distance of each (the
    photo's view lifted onto the light's grid by :func:`roomlight.core.geometry.lift.lift_view`).

    Returns ``(flat texel indices (K,), distances (K,))`` for the K texels holding at least one point.
    """
    from roomlight.core.geometry.lift import lift_view

    points = np.asarray(points, np.float64)
    lifted = lift_view(points, np.zeros_like(points), np.eye(3), resolution)
    hit = np.flatnonzero(lifted.seen.numpy().reshape(-1))
    return hit, np.exp(lifted.log_depth.double().numpy().reshape(-1)[hit])


def case_gap(folder: Path, settings: dict | None = None) -> tuple[np.ndarray, float | None]:
    """log2(fitted depth / photographed distance) over the texels the photograph covers, for one fitted case
    folder (``cases/ID/METHOD``), and, given the run's ``settings`` (``{"preset", "overrides"}``), the share of
    those texels at the containment floor (else None)."""
    from roomlight.core.io import read_panorama
    from roomlight.fitting.photo import case as case_mod
    from roomlight.fitting.photo.masks import erode
    from roomlight.fitting.photo.unproject import unproject

    record = json.loads((folder / "result.json").read_text())
    case = case_mod.load_photo(record["case_dir"])
    pano = read_panorama(folder / "recovered.exr")
    if pano.depth is None:
        raise SystemExit(f"error: {folder}: the recovered light has no depth (an env map?)")
    frame = np.asarray(pano.metadata["light_from_camera"], np.float64)
    points = unproject(case.depth, case.intrinsics, case.depth_kind).reshape(-1, 3)
    background = erode(np.asarray(case.objects.labels) == 0, 1).reshape(-1)
    points = points[background] @ frame[:3, :3].T + frame[:3, 3]
    depth = np.asarray(pano.depth, np.float64)
    hit, distance = seen_texels(points, depth.shape)
    gap = np.log2(depth.reshape(-1)[hit] / distance)
    if settings is None:
        return gap, None
    from roomlight.fitting.photo.config import photo_config
    from roomlight.fitting.photo.fitter import containment_floor, containment_points
    from roomlight.fitting.photo.geometry import SceneTransform, build_geometry

    config = photo_config(settings["preset"], **settings.get("overrides", {}))
    fitted_case = case_mod.load_photo(record["case_dir"], min_object_fraction=config.min_object_fraction)
    contained = containment_points(build_geometry(fitted_case, config), SceneTransform.from_matrix(frame))
    floor = containment_floor(contained, depth.shape, config).double().numpy().reshape(-1)[hit]
    at_floor = (floor > 0) & (np.abs(depth.reshape(-1)[hit] / np.maximum(floor, 1e-12) - 1.0) < 0.01)
    return gap, float(at_floor.mean())


def main(argv=None) -> None:
    from roomlight.errors import RoomlightError

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+", type=Path)
    ap.add_argument("--method", default="prior")
    ap.add_argument("--floor", action="store_true", help="also the share of seen texels at the containment floor")
    args = ap.parse_args(argv)
    for run in args.runs:
        folders = sorted(p / args.method for p in (run / "cases").glob("*") if (p / args.method / "recovered.exr").is_file())
        if not folders:
            sys.exit(f"error: {run}: no case with {args.method}/recovered.exr (a `bench run-photos` folder?)")
        settings = None
        if args.floor:
            if not (run / "run.json").is_file():
                sys.exit(f"error: {run}: no run.json, so the fit's settings (and its floor) are unknown")
            settings = json.loads((run / "run.json").read_text())
        print(f"\n{run}: fitted depth / photographed distance over the seen texels, log2")
        print("| photo | texels | median | mean abs | at the floor |")
        print("|---|:---:|:---:|:---:|:---:|")
        medians, shares = [], []
        for folder in folders:
            try:
                gap, share = case_gap(folder, settings)
            except (RoomlightError, OSError, KeyError, ValueError) as e:
                sys.exit(f"error: {folder}: {e} (has the photo case moved, or is run.json from another version?)")
            medians.append(float(np.median(gap)))
            shares.append(share)
            cell = "" if share is None else f"{share:.2f}"
            print(f"| {folder.parent.name} | {len(gap)} | {medians[-1]:+.3f} | {float(np.abs(gap).mean()):.3f} | {cell} |")
        m = float(np.median(medians))
        floor = "" if settings is None else f"{min(shares):.2f}–{max(shares):.2f}"
        print(f"| median over {len(medians)} photos | | {m:+.3f} ({2 ** m:.3f}x) | | {floor} |")


if __name__ == "__main__":
    main()
