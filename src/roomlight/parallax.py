"""The parallax figure: one room as a 2.5D area light and as an env map, the same probes under both.

The 2.5D area light reproduces position-dependent reflections and falloff; the env map shows
every probe the same distant world. ``roomlight demo`` writes it (``OUT/parallax/``), and the
README's first image is one.
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["PARALLAX_PROBES", "parallax_figure"]

#: Probe spheres ``x,y,z,radius,material`` in metres, in front of the camera (looking along -z).
PARALLAX_PROBES = ["-0.8,-0.65,-2.4,0.33,mirror", "0.7,-0.6,-1.4,0.3,mirror", "-0.05,-1.05,-1.9,0.3,diffuse"]


def parallax_figure(out_dir, rad, depth, res: tuple[int, int] = (192, 192), spp: int = 64) -> dict:
    """Write ``mesh/`` and ``envmap/`` emitter bundles, probe renders under both, and
    ``comparison.png`` to ``out_dir``; returns the mean absolute difference of the two renders.

    Args:
        rad: (H, W, 3) linear radiance; depth: (H, W) radial depth in metres (torch tensors).
        res: (height, width) of the probe renders, pixels.
    """
    import numpy as np

    from roomlight.core.emitter.export import export_emitter
    from roomlight.core.io import save_png, write_exr
    from roomlight.core.io.preview import auto_exposure_stops, tonemap_gamma
    from roomlight.core.render.bundle import parse_probe, render_bundle
    from roomlight.core.render.camera import perspective_sensor

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    for kind in ("mesh", "envmap"):
        export_emitter(out / kind, rad, depth, kind)
    probes = [parse_probe(p) for p in PARALLAX_PROBES]
    # Probes sit 1.4-2.4 m in front of the camera: scale them into small rooms.
    near = float(depth[depth.shape[0] // 2:, :].min())
    scale = min(1.0, 0.8 * near / 2.7)
    probes = [type(p)(tuple(c * scale for c in p.center), p.radius * scale, p.material) for p in probes]
    sensor = perspective_sensor((0.0, 0.0, 0.0), (0.0, -0.65 * scale, -1.8 * scale), (0.0, 1.0, 0.0), 65.0, res[1], res[0])
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

    from roomlight.core.io.preview import auto_exposure_stops, colorize_depth, tonemap_gamma

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
