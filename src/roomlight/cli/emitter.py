"""``roomlight emitter``: turn a panorama into an emitter bundle (PLY + EXR + Mitsuba XML + PNG)."""

from __future__ import annotations

import click

from roomlight.cli.common import HEIGHT, echo_fixes, fail, repair_options


def load_panorama_tensors(pano: str, depth: str | None, resolution: int | None, clamp_negative: bool,
                          fill_nonfinite: float | None):
    """Read a panorama (or the built-in ``example``) as torch (radiance (H,W,3), depth (H,W)|None, meta)."""
    import torch

    from roomlight.core.geometry import resize_panorama

    if pano == "example":
        from roomlight.core.examples import example_room

        rad, dep = example_room(resolution or 128)
        return rad, dep, {"source": "built-in example room"}
    from roomlight.core.io import read_panorama

    import warnings

    with warnings.catch_warnings():  # the fixes are reported below, once, as notes
        warnings.simplefilter("ignore")
        p = read_panorama(pano, depth_path=depth, clamp_negative=clamp_negative, fill_nonfinite=fill_nonfinite)
    echo_fixes(p.fixes)
    rad = torch.from_numpy(p.radiance).float()
    dep = torch.from_numpy(p.depth).float() if p.depth is not None else None
    if resolution and resolution != rad.shape[0]:
        rad = resize_panorama(rad.permute(2, 0, 1)[None], resolution)[0].permute(1, 2, 0)
        if dep is not None:
            dep = resize_panorama(dep[None, None], resolution)[0, 0]
    return rad.contiguous(), (dep.contiguous() if dep is not None else None), dict(p.metadata)


@click.command("emitter")
@click.argument("pano")
@click.option("--depth", "depth_path", type=click.Path(), default=None,
              help="Separate radial depth file (.exr, .npy or 16-bit PNG in mm) when PANO has no depth channel.")
@click.option("--as", "kind", default="mesh", show_default=True, metavar="mesh|envmap|sphere:R",
              help="Representation: the 2.5D area light, an env map at infinity, or a sphere of radius R (metres).")
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False), help="Output directory.")
@click.option("--height", "resolution", type=HEIGHT, default=None,
              help="Resample the panorama to HEIGHT x 2*HEIGHT first (e.g. 128 for the prior's resolution).")
@repair_options
def command(pano, depth_path, kind, out_dir, resolution, clamp_negative, fill_nonfinite):
    """Build an emitter from panorama PANO and write it to --out.

    PANO is an EXR with channels R,G,B,Z (roomlight's format) or R,G,B,A (depth in A, the paper
    authors' layout), or a radiance-only .exr/.hdr together with --depth. The word `example`
    uses the built-in example room.

    \b
    Writes to --out:
      emitter.ply   the mesh (positions + uv), for mesh and sphere emitters
      radiance.exr  the emissive texture (linear RGB, float32); depth.exr holds depth (Z)
      envmap.exr    env maps only: radiance in Mitsuba's envmap row layout
      scene.xml     a Mitsuba 3 scene with the emitter (id "emitter"): mi.load_file(...)
      preview.png   tone-mapped radiance above colour-mapped depth
    """
    from roomlight.core.emitter.export import export_emitter
    from roomlight.core.light import parse_emitter_kind

    k = parse_emitter_kind(kind)
    rad, dep, meta = load_panorama_tensors(pano, depth_path, resolution, clamp_negative, fill_nonfinite)
    if k.name == "mesh" and dep is None:
        fail(f"{pano}: a 2.5D area light needs depth; pass --depth FILE, or use --as envmap / --as sphere:R")
    paths = export_emitter(out_dir, rad, dep, k, metadata={"source": str(pano), **{
        key: v for key, v in meta.items() if isinstance(v, (int, float, str, list))}})
    h, w = rad.shape[:2]
    click.echo(f"{k} emitter from {pano} ({h}x{w}) -> {out_dir}")
    for name, p in paths.items():
        click.echo(f"  {name:<9} {p}")
