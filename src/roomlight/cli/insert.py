"""``roomlight insert``: virtual objects composited into a fitted photograph (differential rendering)."""

from __future__ import annotations

from pathlib import Path

import click

from roomlight.cli.common import parse_reference_albedo


#: an object lit at least this much by the light's unseen part gets a word of caution
UNSEEN_WARNING = 0.5


def _floats(n: int, name: str):
    def convert(ctx, param, value):
        if value is None:
            return None
        try:
            v = tuple(float(x) for x in value.split(","))
        except ValueError:
            v = ()
        if len(v) != n:
            raise click.BadParameter(f"{value!r}: expected {n} comma-separated numbers", param_hint=name)
        return v
    return convert


@click.command("insert")
@click.argument("fit", type=click.Path(exists=True, file_okay=False))
@click.option("--object", "obj", default=None, metavar="MESH|NAME",
              help="An OBJ / PLY / glTF / GLB file, or a built-in shape (sphere, blob, knot, torus, cup, spiky).")
@click.option("--at", callback=_floats(2, "--at"), default=None, metavar="X,Y",
              help="A pixel of the photograph on a visible surface (x right, y down, from 0); the object rests on "
                   "that surface along its normal.")
@click.option("--at-xyz", "at_xyz", callback=_floats(3, "--at-xyz"), default=None, metavar="X,Y,Z",
              help="A point in the camera frame instead (metres; x right, y up, looking along -z), resting on "
                   "the room's floor direction.")
@click.option("--scale", type=float, default=None, metavar="METRES",
              help="Largest side of the object's bounding box [default: 0.15 x its distance from the camera].")
@click.option("--rotate", type=float, default=0.0, show_default=True, metavar="DEG",
              help="Turn the object about the surface normal.")
@click.option("--material", default="diffuse:0.8,0.8,0.8", show_default=True,
              help="mirror | diffuse:R,G,B | principled:ALBEDO,ROUGHNESS,METALLIC (ALBEDO: gray or R,G,B).")
@click.option("--placements", type=click.Path(exists=True, dir_okay=False), default=None,
              help="A YAML / JSON list of objects (keys object, at or at_xyz, scale, rotate, material), "
                   "instead of or besides --object.")
@click.option("--light", default=None, metavar="METHOD",
              help="Which fitted light: the fit's own [default] or a compared method's (FIT/compare/METHOD).")
@click.option("--exposure", "exposure", type=float, default=0.0, show_default=True, metavar="EV",
              help="Make the fitted light 2^EV times as bright and the photograph's objects 2^EV times "
                   "darker (the photograph itself unchanged): the photo fit's largest error is the light's "
                   "level, so if the new objects look too bright next to the real ones, try -1.")
@click.option("--reference-albedo", "reference", default=None, metavar="LABEL=ALBEDO",
              help="Object LABEL of the photograph's mask is known to reflect ALBEDO (its mean over R, G, B; "
                   "a grey card, white paper): the light's level is set so that it does (--exposure is "
                   "then added on top).")
@click.option("--out", "out", required=True, type=click.Path(dir_okay=False),
              help="The composite (sRGB PNG); the EXR, object_mask.png, shadow.png and insert.json go beside it.")
@click.option("--size", type=click.IntRange(min=8), default=512, show_default=True,
              help="Longest side of the composite in pixels (at most the photograph's).")
@click.option("--spp", type=click.IntRange(min=1), default=256, show_default=True,
              help="Samples per pixel of each render.")
@click.option("--seed", type=int, default=0, show_default=True)
def command(fit, obj, at, at_xyz, scale, rotate, material, placements, light, exposure, reference, out, size,
            spp, seed):
    """Put objects into the photograph of a `fit-photo` output folder FIT.

    The photograph's depth mesh becomes the local scene (the fitted objects keep their fitted
    materials, the other surfaces get an albedo estimated from the photograph); it is rendered
    under the recovered light without and with the new objects, with the same seed, and the
    difference is added to the photograph (differential rendering): the objects' shading,
    shadows and reflections all come from the renderer. Composed in linear radiance.

    \b
    Examples:
      roomlight insert out/photo --object sphere --material mirror --at 210,300 --out out/insert/composite.png
      roomlight insert out/photo --placements objects.yaml --light direct-envmap --out out/env/composite.png
    """
    from roomlight.errors import RoomlightError
    from roomlight.fitting.insert import InsertSpec, insert_objects, load_fitted_photo, read_placements, write_insert_outputs

    specs = list(read_placements(placements)) if placements else []
    if obj is not None or at is not None or at_xyz is not None:
        spec = InsertSpec(object=obj or "sphere", at=at, at_xyz=at_xyz, scale=scale, rotate=rotate, material=material)
        spec.check("command line")
        specs.append(spec)
    if not specs:
        raise RoomlightError("nothing to insert: give --object with --at X,Y (or --at-xyz), or --placements FILE")
    fitted = load_fitted_photo(fit, light)
    if reference is not None:
        label, value = parse_reference_albedo(reference)
        exposure += fitted.exposure_for_albedo(label, value)
    if exposure:
        fitted = fitted.with_exposure(exposure)
    result = insert_objects(fitted, specs, size=size, spp=spp, seed=seed, say=lambda m: click.echo(m, err=True))
    if reference is not None:
        result.info["reference_albedo"] = {"label": label, "albedo": value}
    paths = write_insert_outputs(result, out)
    level = f" ({exposure:+.2f} EV)" if exposure else ""
    click.echo(f"{len(specs)} object(s) inserted under the {fitted.method} light{level} in "
               f"{result.info['timings_s']['total']:.1f} s -> {paths['composite_png']} "
               f"(+ {Path(paths['composite_exr']).name}, object_mask.png, shadow.png, insert.json)")
    shares = [o.get("unseen_light_share") for o in result.info["objects"]]
    for k, (o, share) in enumerate(zip(result.info["objects"], shares)):
        if share is not None:
            click.echo(f"  object {k + 1} ({Path(str(o['object'])).name}): {min(max(share, 0.0), 1.0):.0%} of its "
                       "shading from parts of the room the photograph does not show")
    if any(share is not None and share >= UNSEEN_WARNING for share in shares):
        click.echo("  where that share is large, the object's look is the prior's guess of the unseen room, the "
                   "photo fit's least certain part: compare it with a real object of the photograph "
                   "(docs/troubleshooting.md)")
