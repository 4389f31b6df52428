"""``roomlight synth``: render a dataset of procedural rooms (HDR radiance + exact depth)."""

from __future__ import annotations

import json

import click

from roomlight.cli.common import RESOLUTION


#: Default samples per pixel with and without denoising: equal quality (docs/synth.md, Speed).
DENOISED_SPP = 64
PLAIN_SPP = 144


def _shard(text: str) -> tuple[int, int]:
    try:
        i, n = (int(v) for v in text.split("/"))
        if not 0 <= i < n:
            raise ValueError
        return i, n
    except ValueError:
        raise click.BadParameter(f"expected i/n with 0 <= i < n, e.g. 0/4; got {text!r}", param_hint="--shard") from None


@click.command("synth")
@click.option("--n", "n", type=int, default=500, show_default=True, help="Number of rooms (seeds SEED .. SEED+N-1).")
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False), help="Output directory.")
@click.option("--res", type=RESOLUTION, default="128x256", show_default=True, help="Panorama size HxW (W = 2H).")
@click.option("--spp", type=int, default=None,
              help="Samples per pixel, a perfect square. Default: 64 when denoising, else 144.")
@click.option("--seed", "seed0", type=int, default=0, show_default=True, help="First seed.")
@click.option("--shard", default="0/1", show_default=True, help="Render only seeds with seed % n == i (i/n).")
@click.option("--workers", type=int, default=1, show_default=True, help="Worker processes.")
@click.option("--scheduler", default=None, metavar="ADDRESS",
              help="Render on the workers of this Dask scheduler (tcp://host:8786) instead; needs roomlight[dask].")
@click.option("--nadir-cap", type=click.FloatRange(min=0.0, max=90.0, max_open=True), default=0.0, show_default=True,
              help="Simulate a tripod blind spot: black cap of this polar angle (degrees) at the nadir "
                   "(`roomlight prepare` inpaints it).")
@click.option("--denoise/--no-denoise", default=None,
              help="Denoise with Intel OIDN (pyoidn, installed by `make setup`); light sources keep their exact "
                   "values. Default: on when pyoidn can be imported. 64 spp denoised matches 256 spp "
                   "without it at 4x the speed (docs/synth.md).")
@click.option("--no-summary", is_flag=True, help="Skip stats.json and the contact sheet.")
def command(n, out_dir, res, spp, seed0, shard, workers, scheduler, nadir_cap, denoise, no_summary):
    """Render N procedural rooms into OUT as panorama EXRs (R,G,B + Z depth in metres).

    Each seed is a random room (box, L-shaped, alcove or a large hall; furniture; doors; windows with sky and
    sun, ceiling lights, lamps, screens) path-traced from its capture point with Mitsuba.
    Samples go to OUT/train, OUT/val and OUT/test by seed range (80/10/10 %). Re-running the
    same command skips finished samples. Also writes OUT/stats.json and OUT/contact_sheet.png.
    """
    from roomlight.datagen.synth.dataset import (
        SynthConfig,
        contact_sheet,
        generate_dataset,
        write_stats,
    )

    from roomlight.datagen.synth.denoise import denoise_available

    h, w = res
    if denoise is None:
        denoise = denoise_available()
        if not denoise:
            click.echo("pyoidn is not installed: rendering without denoising (`pip install pyoidn` to denoise)",
                       err=True)
    if spp is None:
        spp = DENOISED_SPP if denoise else PLAIN_SPP
    if w != 2 * h:
        raise click.BadParameter(f"panoramas are H x 2H, got {h}x{w}", param_hint="--res")
    cfg = SynthConfig(n=n, seed0=seed0, height=h, spp=spp, shard=_shard(shard), workers=max(1, workers),
                      nadir_cap=nadir_cap, denoise=denoise, scheduler=scheduler)
    summary = generate_dataset(out_dir, cfg)
    click.echo(json.dumps(summary))
    if not no_summary:
        stats = write_stats(out_dir)
        sheet = contact_sheet(out_dir)
        click.echo(f"{stats['samples']} samples ({stats['splits']}); stats.json and {sheet} written")
    if summary["failed"]:
        raise SystemExit(1)
