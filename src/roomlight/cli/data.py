"""``roomlight data``: dataset tools (normalisation statistics, packed cache, toy rooms)."""

from __future__ import annotations

import json
from pathlib import Path

import click

from roomlight.cli.common import HEIGHT, RESOLUTION, RoomlightGroup, fail, repair_options
from roomlight.prior.model.config import PRESETS


def _resolution(res, preset):
    if res is not None:
        h, w = res
        if w != 2 * h:
            raise click.BadParameter(f"expected HxW with W = 2H, got {h}x{w}", param_hint="--res")
        return h, w
    from roomlight.prior.model import get_preset

    return get_preset(preset).resolution


@click.group("data", cls=RoomlightGroup)
def command():
    """Dataset tools: statistics for the prior's normalisation, the packed cache, toy rooms."""


@command.command("stats")
@click.argument("data_dir", type=click.Path(exists=True, file_okay=False))
@click.option("--res", type=RESOLUTION, default=None, help="Training resolution HxW (default: the --config model's).")
@click.option("--config", "preset", default="default", show_default=True,
              type=click.Choice(list(PRESETS)), help="Model preset giving the resolution.")
@click.option("--split", default="train", show_default=True, type=click.Choice(["train", "val", "test", "all"]))
@click.option("--depth-units", default="metres", show_default=True, type=click.Choice(["metres", "scale-free"]))
@click.option("--no-calibrate", is_flag=True, help="Do not exposure-calibrate radiance (it normally is).")
@click.option("--out", "out_path", type=click.Path(dir_okay=False), default=None,
              help="Write the statistics as JSON here (default: DATA_DIR/stats-HxW.json).")
@repair_options
def stats(data_dir, res, preset, split, depth_units, no_calibrate, out_path, clamp_negative, fill_nonfinite):
    """Normalisation statistics (mean/std of log1p RGB and log depth) and a data summary.

    The statistics are what `roomlight train` computes at its start and stores in the model;
    bad files are listed by name and skipped.
    """
    from roomlight.prior.data import PanoramaDataset, dataset_statistics, split_files

    h, w = _resolution(res, preset)
    splits = split_files(data_dir)
    files = [f for s in splits.values() for f in s] if split == "all" else splits[split]
    ds = PanoramaDataset(files, (h, w), root=data_dir, calibrate=not no_calibrate, depth_units=depth_units,
                         clamp_negative=clamp_negative, fill_nonfinite=fill_nonfinite)
    st = dataset_statistics(ds)
    for item in st["skipped"]:
        click.echo(f"skipped {item['name']}: {item['reason']}", err=True)
    if st["count"] == 0:
        fail(f"no usable panorama in {data_dir}")
    st.update({"split": split, "calibrated": not no_calibrate, "depth_units": depth_units, "data": str(data_dir)})
    out = Path(out_path) if out_path else Path(data_dir) / f"stats-{h}x{w}.json"
    out.write_text(json.dumps(st, indent=2) + "\n")
    n = st["normalization"]
    click.echo(f"{st['count']} panoramas at {h}x{w} ({split}), {len(st['skipped'])} skipped")
    if n is not None:
        click.echo("channel      mean      std")
        for c, m, s in zip(n["channels"], n["mean"], n["std"]):
            click.echo(f"{c:<10} {m:8.4f} {s:8.4f}")
    click.echo(f"-> {out}")


@command.command("pack")
@click.argument("data_dir", type=click.Path(exists=True, file_okay=False))
@click.option("--res", type=RESOLUTION, default=None, help="Training resolution HxW (default: the --config model's).")
@click.option("--config", "preset", default="default", show_default=True,
              type=click.Choice(list(PRESETS)))
@click.option("--dtype", default="float16", show_default=True, type=click.Choice(["float16", "float32"]))
@click.option("--depth-units", default="metres", show_default=True, type=click.Choice(["metres", "scale-free"]))
@click.option("--workers", type=int, default=2, show_default=True, help="Processes decoding EXRs.")
def pack(data_dir, res, preset, dtype, depth_units, workers):
    """Build the packed cache `roomlight train` reads (otherwise built on first use)."""
    from roomlight.prior.data import PackedCache, split_files

    h, w = _resolution(res, preset)
    files = [f for s in split_files(data_dir).values() for f in s]
    cache = PackedCache.open_or_build(data_dir, files, (h, w), dtype=dtype, depth_units=depth_units,
                                      workers=workers, log=lambda m: click.echo(m, err=True))
    click.echo(f"{cache.manifest['count']} panoramas packed, {len(cache.errors)} skipped -> {cache.path}")


@command.command("toy")
@click.option("--n", "count", type=int, default=64, show_default=True)
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False))
@click.option("--height", type=HEIGHT, default=32, show_default=True, help="Panorama height (width 2x).")
@click.option("--seed", type=int, default=0, show_default=True)
def toy(count, out_dir, height, seed):
    """Write analytic toy box rooms (exact depth, a panel and/or window light) for smoke runs.

    Not a substitute for `roomlight synth` rooms: no path tracing, no furniture.
    """
    from roomlight.prior.data import write_toy_dataset

    paths = write_toy_dataset(out_dir, count, height, seed)
    click.echo(f"wrote {len(paths)} toy panoramas ({height}x{2 * height}) to {out_dir}")
