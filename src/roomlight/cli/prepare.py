"""``roomlight prepare``: real HDR panoramas (no depth, a tripod blind spot) -> training data."""

from __future__ import annotations

import json

import click

from roomlight.cli.common import RESOLUTION, fail, repair_options


def _nadir(text: str) -> str:
    t = str(text).strip().lower()
    if t in ("auto", "off"):
        return t
    try:
        deg = float(t)
    except ValueError:
        raise click.BadParameter(f"expected auto, off or a cap in degrees (e.g. 20), got {text!r}",
                                 param_hint="--nadir") from None
    if not 0.0 < deg <= 60.0:
        raise click.BadParameter(f"the cap must be in (0, 60] degrees from the nadir, got {text!r}",
                                 param_hint="--nadir")
    return repr(deg)


def _split(text: str):
    t = str(text).strip().lower()
    if t == "none":
        return None
    try:
        parts = [float(v) for v in t.split("/")]
        if len(parts) != 3 or any(p < 0 for p in parts) or sum(parts) <= 0 or parts[0] <= 0:
            raise ValueError
    except ValueError:
        raise click.BadParameter(f"expected TRAIN/VAL/TEST percentages like 80/10/10, or none; got {text!r}",
                                 param_hint="--split") from None
    total = sum(parts)
    return tuple(p / total for p in parts)


@click.command("prepare")
@click.argument("input_dir", metavar="IN", type=click.Path(exists=True, file_okay=False))
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False), help="Output dataset folder.")
@click.option("--nadir", default="auto", show_default=True, metavar="auto|off|DEG",
              help="The tripod blind spot: detect its extent (auto), leave the nadir as it is (off), or "
                   "inpaint a cap of DEG degrees around the nadir.")
@click.option("--inpainter", default="telea", show_default=True, metavar="NAME",
              help="telea or ns (OpenCV, built in), lama[:WEIGHTS] (simple-lama-inpainting and big-lama.pt), "
                   "or MODULE:FUNCTION taking (image, mask).")
@click.option("--depth", default="keep", show_default=True, metavar="ESTIMATOR",
              help="keep (the input's own Z channel), moge[:WEIGHTS] (MoGe and a model.pt), "
                   "synthetic[:affine|scale|metric] (the true depth distorted like a network's, for tests), "
                   "or MODULE:FUNCTION taking a view.")
@click.option("--truth", "truth_dir", default=None, type=click.Path(exists=True, file_okay=False),
              help="Folder of true depth files NAME.exr (Z) / .npy / .png (mm) for --depth synthetic; "
                   "default: the input's own Z channel.")
@click.option("--camera-height", type=click.FloatRange(min=0, min_open=True), default=1.6, show_default=True,
              help="Metres from the floor to the camera: the depth of a non-metric estimator is scaled so the "
                   "floor lies this far below.")
@click.option("--res", type=RESOLUTION, default=None, help="Output size HxW (W = 2H). Default: each input's own.")
@click.option("--split", "split_text", default="80/10/10", show_default=True, metavar="T/V/T|none",
              help="Percentages of train/val/test (by a hash of the file name), or none for one flat folder.")
@click.option("--view-size", type=click.IntRange(min=16, max=2048), default=None,
              help="Size of the 12 depth views in pixels [default: twice the panorama's angular resolution].")
@click.option("--max-cap", type=click.FloatRange(min=0, max=90, min_open=True), default=45.0, show_default=True,
              help="--nadir auto skips a file whose dark region reaches further from the nadir.")
@click.option("--workers", type=click.IntRange(min=1), default=1, show_default=True, help="Worker processes.")
@click.option("--no-previews", is_flag=True, help="Skip OUT/previews/NAME.png (radiance above depth).")
@click.option("--no-summary", is_flag=True, help="Skip stats.json and the contact sheet.")
@repair_options
def command(input_dir, out_dir, nadir, inpainter, depth, truth_dir, camera_height, res, split_text, view_size,
            max_cap, workers, no_previews, no_summary, clamp_negative, fill_nonfinite):
    """Turn a folder IN of HDR panoramas (.exr, .hdr; W = 2H) into training data in OUT.

    Each panorama's tripod blind spot is inpainted in a gnomonic view of the nadir (tone mapped,
    inpainted, mapped back exactly; pixels outside the cap are untouched), its depth is kept or
    estimated from 12 tangent views fused by a global scale (and shift) solve, and it is written
    as OUT/SPLIT/NAME.exr (R,G,B + Z metres, exposure calibrated), as `roomlight synth` writes
    them. Inputs that cannot be used are skipped and named; re-running resumes. Also writes
    OUT/prepare-log.jsonl (what was done to each file), OUT/stats.json, OUT/contact_sheet.png
    and OUT/previews/.
    """
    from roomlight.datagen.prepare.dataset import PrepareConfig, prepare_folder

    if res is not None and res[1] != 2 * res[0]:
        raise click.BadParameter(f"panoramas are H x 2H, got {res[0]}x{res[1]}", param_hint="--res")
    if truth_dir and not str(depth).startswith("synthetic"):
        fail("--truth is the true depth for --depth synthetic; it is not used by --depth " + str(depth))
    cfg = PrepareConfig(nadir=_nadir(nadir), inpainter=inpainter, depth=depth, truth=truth_dir,
                        camera_height=camera_height, resolution=tuple(res) if res else None,
                        split=_split(split_text), view_size=view_size, max_cap=max_cap, workers=workers,
                        clamp_negative=clamp_negative, fill_nonfinite=fill_nonfinite, previews=not no_previews)
    summary = prepare_folder(input_dir, out_dir, cfg)
    outputs = summary.pop("outputs")
    click.echo(json.dumps(summary))
    if outputs and not no_summary:
        from pathlib import Path

        from roomlight.datagen.synth.dataset import contact_sheet, write_stats

        files = [Path(out_dir) / o for o in outputs]
        stats = write_stats(out_dir, files=files)
        sheet = contact_sheet(out_dir, files=files)
        click.echo(f"{stats['samples']} panoramas ({stats['splits']}); stats.json and {sheet} written")
    for name, reason in summary["skipped"].items():
        click.echo(f"skipped {name}: {reason}", err=True)
    if summary["skipped"]:
        raise SystemExit(1)
