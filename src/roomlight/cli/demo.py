"""``roomlight demo``: the built-in end-to-end example (see :mod:`roomlight.demo`)."""

from __future__ import annotations

from pathlib import Path

import click

from roomlight.cli.common import HEIGHT, RESOLUTION
from roomlight.demo import DEMO_ROOMS, DemoConfig

MATERIALS = ("diffuse", "matte", "mirror")


def _room_option(text: str) -> tuple[int, str]:
    """'SEED:MATERIAL' -> (seed, material), or a usage error naming the option."""
    seed, sep, material = text.partition(":")
    try:
        value = int(seed)
    except ValueError:
        value = None
    if not sep or value is None or material not in MATERIALS:
        raise click.BadParameter(f"{text!r}: expected SEED:MATERIAL with an integer seed and a material among "
                                 f"{', '.join(MATERIALS)}, e.g. 400201:matte", param_hint="--room")
    return value, material


@click.command("demo")
@click.option("--out", "out_dir", default="roomlight-demo", show_default=True, type=click.Path(file_okay=False))
@click.option("--height", type=HEIGHT, default=DemoConfig.height, show_default=True,
              help="Panorama height (width is twice this).")
@click.option("--res", type=RESOLUTION, default=f"{DemoConfig.res[0]}x{DemoConfig.res[1]}", show_default=True,
              help="Benchmark image size HxW (one number: square).")
@click.option("--iterations", type=int, default=DemoConfig.iterations, show_default=True,
              help="Fitting iterations per method.")
@click.option("--spp", type=int, default=DemoConfig.spp, show_default=True, help="Samples per pixel per fitting step.")
@click.option("--gt-spp", type=int, default=DemoConfig.gt_spp, show_default=True,
              help="Samples per pixel of ground-truth and evaluation renders.")
@click.option("--room", "rooms", multiple=True, metavar="SEED:MATERIAL",
              help="A procedural room and its material (diffuse, matte or mirror); repeat for several. "
                   "[default: " + ", ".join(f"{s}:{m}" for s, m in DEMO_ROOMS) + ", seeds the bundled prior never saw]")
def command(out_dir, height, res, iterations, spp, gt_spp, rooms):
    """Run the built-in example end to end, with nothing downloaded.

    Three procedural rooms, one material each, become 2.5D area lights; a benchmark scene is
    built from each; their illumination is recovered from an image of two objects with the prior
    (the bundled checkpoint when present, else the direct 2.5D baseline) and with the env-map
    baseline; a held-out probe is relit by each. Prints each room and the mean; open
    OUT/report/index.html and OUT/parallax/comparison.png.
    """
    from roomlight.demo import run_demo

    parsed = tuple(_room_option(r) for r in rooms) if rooms else DEMO_ROOMS
    s = run_demo(DemoConfig(out=Path(out_dir), height=height, res=res, iterations=iterations, spp=spp, gt_spp=gt_spp,
                            rooms=parsed))
    click.echo(f"demo finished in {s['seconds']} s ({s['variant']}); open {Path(out_dir) / 'report' / 'index.html'} "
               f"and {Path(out_dir) / 'parallax' / 'comparison.png'}")
