"""``roomlight estimate``: a room's light from one ordinary photograph, in seconds."""

from __future__ import annotations

import click

from roomlight.cli.common import FINITE, load_prior
from roomlight.fitting.photo.estimate import REFINE_STEPS


@click.command("estimate")
@click.argument("photo", type=click.Path())
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False), help="Output directory.")
@click.option("--fov", type=FINITE, default=None, metavar="DEG",
              help="Horizontal field of view in degrees [default: from the EXIF focal length, else 60].")
@click.option("--pitch", type=FINITE, default=0.0, show_default=True, metavar="DEG",
              help="Camera tilt, positive looking up.")
@click.option("--roll", type=FINITE, default=0.0, show_default=True, metavar="DEG",
              help="Camera roll about its view axis.")
@click.option("--depth", type=click.Path(), default=None,
              help="The photograph's depth when you have one (.npy/.exr/.png as for fit-photo; metres), instead "
                   "of the guess.")
@click.option("--depth-kind", type=click.Choice(["z", "radial"]), default="z", show_default=True,
              help="What --depth holds: distance along the optical axis or from the camera centre.")
@click.option("--model", type=click.Path(), default=None,
              help="A prior with a view encoder (a model folder or training run) [default: the bundled prior].")
@click.option("--depth-optional-encoder", "depth_optional", is_flag=True,
              help="Without --depth, read the photograph with the prior's depth-optional view encoder "
                   "(view_encoder_depth_optional/, trained with `train-view-encoder --set depth_dropout=0.5`) "
                   "instead of the guess; it judges the room's size from the photograph (docs/photo.md).")
@click.option("--refine", is_flag=True,
              help="Continue with a short fit of the light to the photograph's own pixels (a few seconds more).")
@click.option("--steps", type=click.IntRange(min=1), default=REFINE_STEPS, show_default=True,
              help="Steps of --refine.")
@click.option("--quiet", is_flag=True, help="Only errors and notes.")
def command(photo, out_dir, fov, pitch, roll, depth, depth_kind, model, depth_optional, refine, steps, quiet):
    """Recover the room's light from PHOTO alone: a JPEG, PNG or linear EXR; no depth, no mask.

    The field of view comes from the EXIF focal length when the file has one (else --fov, else
    60 degrees, with a note). The prior's view encoder reads the photograph with a guessed depth
    (a floor 1.5 m below the camera, the rest 3.5 m away; docs/photo.md, "From any photograph").

    \b
    Writes to --out:
      panorama.exr   recovered radiance (R,G,B, the photograph's units) + radial depth (Z, metres)
      emitter/       the light as an emitter bundle (PLY + EXR + Mitsuba XML)
      probes.png     diffuse, matte and mirror spheres under the light, beside the photograph
      result.json    field of view and its source, exposure, refinement, timings
    """
    import json
    import time
    from pathlib import Path

    import numpy as np
    import torch

    t0 = time.perf_counter()
    from roomlight.core.emitter.export import export_emitter
    from roomlight.core.io import save_png, write_panorama
    from roomlight.core.io.preview import tonemap_gamma
    from roomlight.fitting.photo.estimate import estimate_light, read_photo_for_estimate, sphere_probes

    image, camera, about = read_photo_for_estimate(photo, fov)
    for note in about.pop("notes"):
        click.echo(f"note: {note}", err=True)
    radial = None
    if depth is not None:
        from roomlight.errors import InputFileError
        from roomlight.fitting.photo.case import read_photo_depth
        from roomlight.fitting.photo.unproject import radial_distance

        d = read_photo_depth(depth)
        if d.shape != image.shape[:2]:
            raise InputFileError(depth, f"depth is {d.shape[1]}x{d.shape[0]} but the photograph is "
                                        f"{image.shape[1]}x{image.shape[0]}")
        radial = radial_distance(d, camera, depth_kind).astype(np.float32)
    prior, model_path = load_prior(model, "estimate", device="cuda" if torch.cuda.is_available() else "cpu")
    est = estimate_light(np.minimum(image, 1.0), camera, prior, pitch, roll, refine_steps=steps if refine else 0,
                         depth=radial, without_depth="withheld" if depth_optional else "guess")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    rad, depth = est.light.to_numpy()
    write_panorama(out / "panorama.exr", (rad, depth), half=False,
                   metadata={"emitter_kind": "mesh", "light_from_camera": np.asarray(est.light.frame).tolist(),
                             "units": "the photograph's linear radiance; depth in metres"})
    export_emitter(out / "emitter", torch.as_tensor(rad), torch.as_tensor(depth), "mesh",
                   metadata={"source": str(photo), "command": "roomlight estimate"})
    probes = sphere_probes(est.light, size=min(camera.height, 160))
    # the photograph and the three spheres, at the photograph's exposure (what it would show)
    thumb_w = max(1, round(camera.width * probes["diffuse"].shape[0] / camera.height))
    from roomlight.fitting.photo.geometry import resize_image

    row = [resize_image(image, probes["diffuse"].shape[0], thumb_w)] + [probes[m] for m in ("diffuse", "matte", "mirror")]
    save_png(out / "probes.png", tonemap_gamma(np.concatenate(row, 1)))
    record = {"format": "roomlight.estimate", "photo": str(Path(photo).resolve()), "width": camera.width,
              "height": camera.height, **about, "pitch_deg": pitch, "roll_deg": roll, "model": model_path,
              "log_exposure": est.log_exposure, "latent_norm": float(est.latent.norm()), **est.info,
              "seconds_total": round(time.perf_counter() - t0, 3),
              "files": {"panorama": "panorama.exr", "emitter": "emitter/", "probes": "probes.png"}}
    (out / "result.json").write_text(json.dumps(record, indent=2))
    if not quiet:
        click.echo(f"{photo}: {camera.width}x{camera.height}, {about['fov_deg']:.1f} deg ({about['fov_from']}) -> {out} "
                   f"({record['seconds_total']:.1f} s)")
