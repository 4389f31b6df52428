"""``roomlight view``: an interactive HTML page of a 2.5D area light (one file, works offline)."""

from __future__ import annotations

import click

from roomlight.cli.common import fail


@click.command("view")
@click.argument("path", type=click.Path())
@click.option("--out", "out", required=True, type=click.Path(dir_okay=False), help="The HTML page to write.")
@click.option("--scene", type=click.Path(dir_okay=False), default=None,
              help="A scene description whose objects to show (found by itself for benchmark cases).")
@click.option("--cube-size", type=int, default=128, show_default=True,
              help="Cube-map face size the probe is lit from (pixels).")
def command(path, out, scene, cube_size):
    """Write a viewer page for the light at PATH: an emitter bundle, a `roomlight fit` output,
    a `roomlight sample` output (or one sample_NNN/), a benchmark case or its scene file.

    The page shows the emissive mesh from inside (drag to orbit, W A S D to walk), the capture
    point, the scene's objects, and a probe sphere you drag around: it is lit by the 2.5D light
    at its own position, next to the same probe under the env map of the same panorama.
    """
    from roomlight.export import load_light
    from roomlight.viewer import write_viewer

    light = load_light(path, scene=scene)
    try:
        page = write_viewer(light, out, cube_size=cube_size)
    except FileNotFoundError as e:
        fail(str(e))
    h, w = light.radiance.shape[:2]
    click.echo(f"viewer for {light.source} ({h}x{w}, {len(light.objects)} scene objects) -> {page} "
               f"({page.stat().st_size / 1e6:.1f} MB)")
