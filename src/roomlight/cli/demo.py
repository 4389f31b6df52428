"""``roomlight demo``: the built-in end-to-end example (see :mod:`roomlight.demo`)."""

from __future__ import annotations

from pathlib import Path

import click

from roomlight.cli.common import HEIGHT, RESOLUTION
from roomlight.demo import DemoConfig


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
@click.option("--material", type=click.Choice(["diffuse", "matte", "mirror"]), default=DemoConfig.material,
              show_default=True)
@click.option("--seed", type=int, default=DemoConfig.seed, show_default=True,
              help="Procedural room seed (the default lies outside the bundled prior's training seeds).")
def command(out_dir, height, res, iterations, spp, gt_spp, material, seed):
    """Run the built-in example end to end, with nothing downloaded.

    A room (procedural, or the built-in example room) becomes a 2.5D area light; a benchmark
    scene is built from it; its illumination is recovered from an image of two objects with the
    prior (the bundled checkpoint when present, else the direct 2.5D baseline) and with the
    env-map baseline; a held-out probe is relit by each. Open OUT/report/index.html.
    """
    from roomlight.demo import run_demo

    s = run_demo(DemoConfig(out=Path(out_dir), height=height, res=res, iterations=iterations, spp=spp, gt_spp=gt_spp,
                            material=material, seed=seed))
    click.echo(f"demo finished in {s['seconds']} s ({s['variant']}); open {Path(out_dir) / 'report' / 'index.html'} "
               f"and {Path(out_dir) / 'parallax' / 'comparison.png'}")
