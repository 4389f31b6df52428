"""``roomlight render``: render a view of an emitter scene written by ``roomlight emitter``."""

from __future__ import annotations

from pathlib import Path

import click

from roomlight.cli.common import RESOLUTION, VEC3


@click.command("render")
@click.argument("scene", type=click.Path())
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False), help="Output directory.")
@click.option("--origin", type=VEC3, default="0,0,0", show_default=True, help="Camera position (metres).")
@click.option("--look-at", "target", type=VEC3, default="0,0,-1", show_default=True, help="Point the camera looks at.")
@click.option("--up", type=VEC3, default="0,1,0", show_default=True, help="Camera up vector.")
@click.option("--fov", type=float, default=65.0, show_default=True, help="Horizontal field of view (degrees).")
@click.option("--res", "res", type=RESOLUTION, default="256x256", show_default=True, help="Image size HxW.")
@click.option("--spp", type=int, default=64, show_default=True, help="Samples per pixel.")
@click.option("--seed", type=int, default=0, show_default=True)
@click.option("--max-depth", type=int, default=4, show_default=True, help="Longest light path (bounces + 1).")
@click.option("--sphere", "spheres", multiple=True, metavar="x,y,z,r[,material]",
              help="Add a probe sphere (materials: diffuse, matte, mirror, glossy, white). Repeatable.")
@click.option("--exposure", type=float, default=0.0, show_default=True, help="PNG exposure in stops.")
@click.option("--name", default="render", show_default=True, help="Base name of the output files.")
def command(scene, out_dir, origin, target, up, fov, res, spp, seed, max_depth, spheres, exposure, name):
    """Render SCENE (a directory from `roomlight emitter`, or its scene.xml) to EXR + PNG.

    Example: two mirror spheres at different places reflect different parts of a 2.5D area
    light, while under an env map they look the same:

    \b
      roomlight render out/room --sphere -0.8,-0.5,-2,0.3 --sphere 0.8,-0.5,-1.2,0.3 --out out/r
    """
    from roomlight.core.io import save_png, write_exr
    from roomlight.core.io.preview import tonemap_gamma
    from roomlight.core.render.bundle import parse_probe, render_bundle
    from roomlight.core.render.camera import perspective_sensor

    probes = [parse_probe(s) for s in spheres]
    if spp <= 0:
        raise click.BadParameter("must be positive", param_hint="--spp")
    height, width = res
    sensor = perspective_sensor(origin, target, up, fov, width, height)
    img = render_bundle(scene, sensor, probes, spp=spp, seed=seed, max_depth=max_depth)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    arr = img.numpy()
    write_exr(out / f"{name}.exr", {"R": arr[..., 0], "G": arr[..., 1], "B": arr[..., 2]}, half=False)
    save_png(out / f"{name}.png", tonemap_gamma(arr, exposure_stops=exposure))
    click.echo(f"rendered {height}x{width} (HxW) at {spp} spp -> {out / (name + '.exr')}, {out / (name + '.png')}")
