"""``roomlight export``: a 2.5D area light as glTF binary, USD or OBJ + MTL for other tools."""

from __future__ import annotations

from pathlib import Path

import click

from roomlight.errors import RoomlightError
from roomlight.export.formats import FORMATS


@click.command("export")
@click.argument("path", type=click.Path())
@click.option("--format", "fmt", type=click.Choice(FORMATS), default=None,
              help="Output format (default: from the suffix of --out).")
@click.option("--out", "out", default=None, type=click.Path(dir_okay=False),
              help="The file to write (light.glb, light.usda / .usd / .usdc, light.obj) [default, for a folder "
                   "and --format: PATH/export/light.<format>].")
@click.option("--exposure", type=float, default=0.0, show_default=True, metavar="EV",
              help="Export the light 2^EV times as bright (what `roomlight insert --exposure` renders with: "
                   "the photo fit's largest error is the light's level).")
@click.option("--reference-albedo", "reference", default=None, metavar="LABEL=ALBEDO",
              help="A fit-photo folder only: set the light's level so that object LABEL of the photograph "
                   "has mean albedo ALBEDO, as `roomlight insert --reference-albedo` does (--exposure is "
                   "added on top).")
def command(path, fmt, out, exposure, reference):
    """Export the light at PATH (an emitter bundle, fit or fit-photo output, sample or benchmark case).

    A fit-photo folder also gives the photograph's camera (pose and intrinsics), its depth mesh
    (marked as a shadow catcher) and the photograph as a backplate (<stem>_backplate.png/.exr),
    plus <stem>_blender.py, which opens the file in Blender ready for Cycles (see docs/photo.md):
    blender --python light_blender.py -- light.usda

    \b
    glb  glTF 2.0 binary: the mesh with an 8-bit sRGB emissive texture and
         KHR_materials_emissive_strength s; radiance = srgb_to_linear(texel) * s
    usd  UsdGeom.Mesh with a UsdPreviewSurface whose emissiveColor reads the float EXR
    obj  OBJ + MTL (Ke s s s, map_Ke PNG)
    Every format also writes <stem>_radiance.exr, the exact float radiance.
    """
    from roomlight.export import export_light, load_light

    if out is None:
        if fmt is None or not Path(path).is_dir():
            raise click.UsageError("pass --out FILE (or --format with a folder PATH: PATH/export/light.<format>)")
        out = str(Path(path) / "export" / f"light.{'usda' if fmt == 'usd' else fmt}")
    if fmt is None and Path(out).suffix.lstrip(".").lower() not in (*FORMATS, "usda", "usdc", "gltf"):
        raise click.BadParameter(f"cannot tell the format from {out!r}; pass --format {'|'.join(FORMATS)}",
                                 param_hint="--out")
    light = load_light(path)
    if reference is not None:
        from roomlight.cli.common import parse_reference_albedo

        if light.photo is None:
            raise RoomlightError(f"--reference-albedo needs a fit-photo output folder; {path} is not one")
        label, value = parse_reference_albedo(reference)
        exposure += light.photo.exposure_for_albedo(label, value)
    if exposure:
        light = light.with_exposure(exposure)
    files = export_light(light, out, fmt)
    if light.camera is not None and "intrinsics" in light.camera and Path(out).suffix.lower() != ".obj":
        import shutil

        from roomlight.export import blender_setup

        files["blender_script"] = Path(out).with_name(f"{Path(out).stem}_blender.py")
        shutil.copyfile(blender_setup.__file__, files["blender_script"])
    level = f" ({exposure:+.2f} EV)" if exposure else ""
    click.echo(f"{light.source}{level} -> {out}")
    for name, p in files.items():
        click.echo(f"  {name:<9} {p} ({p.stat().st_size / 1e3:.0f} kB)")
