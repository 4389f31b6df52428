"""``roomlight demo``: the built-in end-to-end example (see :mod:`roomlight.demo`).

This module also holds the parallax figure: a room lifted into a 2.5D area light and into an
env map, with the same probe spheres rendered under both. The 2.5D area light reproduces
position-dependent reflections and falloff; the env map shows every probe the same distant world.
"""

from __future__ import annotations

from pathlib import Path

import click

from roomlight.demo import PARALLAX_PROBES, DemoConfig


def parallax_figure(out_dir, rad, depth, res: int = 192, spp: int = 64) -> dict:
    """Write ``mesh/`` and ``envmap/`` emitter bundles, probe renders under both, and
    ``comparison.png`` to ``out_dir``; returns the mean absolute difference of the two renders."""
    import numpy as np

    from roomlight.emitter.export import export_emitter
    from roomlight.io import save_png, write_exr
    from roomlight.io.preview import auto_exposure_stops, tonemap_gamma
    from roomlight.render.bundle import parse_probe, render_bundle
    from roomlight.render.camera import perspective_sensor

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    for kind in ("mesh", "envmap"):
        export_emitter(out / kind, rad, depth, kind)
    probes = [parse_probe(p) for p in PARALLAX_PROBES]
    # Probes sit 1.4-2.4 m in front of the camera: scale them into small rooms.
    near = float(depth[depth.shape[0] // 2:, :].min())
    scale = min(1.0, 0.8 * near / 2.7)
    probes = [type(p)(tuple(c * scale for c in p.center), p.radius * scale, p.material) for p in probes]
    sensor = perspective_sensor((0.0, 0.0, 0.0), (0.0, -0.65 * scale, -1.8 * scale), (0.0, 1.0, 0.0), 65.0, res, res)
    renders = {}
    for kind in ("mesh", "envmap"):
        img = render_bundle(out / kind, sensor, probes, spp=spp).numpy()
        renders[kind] = img
        write_exr(out / f"probes_{kind}.exr", {"R": img[..., 0], "G": img[..., 1], "B": img[..., 2]})
    # One exposure for both renders (so they compare), set by the 2.5D render's auto-exposure.
    stops = auto_exposure_stops(renders["mesh"])
    for kind, img in renders.items():
        save_png(out / f"probes_{kind}.png", tonemap_gamma(img, stops))
    _comparison_png(out / "comparison.png", rad.numpy(), depth.numpy(), renders, stops)
    return {"mean_abs_difference_envmap_vs_mesh": float(np.abs(renders["envmap"] - renders["mesh"]).mean())}


def _comparison_png(path, rad, depth, renders, stops: float):
    """The panorama (auto-exposed), its depth, the probes under both lights (exposed by
    ``stops``) and their difference."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    from roomlight.io.preview import auto_exposure_stops, colorize_depth, tonemap_gamma

    fig = plt.figure(figsize=(12, 7.2), dpi=110)
    grid = fig.add_gridspec(2, 3, height_ratios=[1, 1.6])
    ax = fig.add_subplot(grid[0, 0:2])
    ax.imshow(tonemap_gamma(rad, auto_exposure_stops(rad)))
    ax.set_title("HDR radiance (auto-exposed)")
    ax.axis("off")
    ax = fig.add_subplot(grid[0, 2])
    ax.imshow(colorize_depth(depth))
    ax.set_title("radial depth")
    ax.axis("off")
    for col, (kind, title) in enumerate([("mesh", "lit by the 2.5D area light"), ("envmap", "lit by an env map")]):
        ax = fig.add_subplot(grid[1, col])
        ax.imshow(tonemap_gamma(renders[kind], stops))
        ax.set_title(title)
        ax.axis("off")
    ax = fig.add_subplot(grid[1, 2])
    err = np.abs(renders["envmap"] - renders["mesh"]).mean(-1)
    im = ax.imshow(err, cmap="magma", vmin=0, vmax=max(float(np.percentile(err, 99)), 1e-6))
    ax.set_title("|env map - 2.5D| (parallax error)")
    ax.axis("off")
    fig.colorbar(im, ax=ax, fraction=0.046)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


@click.command("demo")
@click.option("--out", "out_dir", default="roomlight-demo", show_default=True, type=click.Path(file_okay=False))
@click.option("--height", type=int, default=DemoConfig.height, show_default=True,
              help="Panorama height (width is twice this).")
@click.option("--res", type=int, default=DemoConfig.res, show_default=True, help="Benchmark image size (pixels).")
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

    s = run_demo(DemoConfig(Path(out_dir), height, res, iterations, spp, gt_spp, material, seed))
    click.echo(f"demo finished in {s['seconds']} s ({s['variant']}); open {Path(out_dir) / 'report' / 'index.html'} "
               f"and {Path(out_dir) / 'parallax' / 'comparison.png'}")
