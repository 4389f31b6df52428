"""``roomlight fit-photo``: the room's light and the objects' materials from one photograph."""

from __future__ import annotations

import click

from roomlight.cli.common import FINITE, default_of, load_prior, parse_sets, set_view_encoder
from roomlight.fitting.methods import method as method_record
from roomlight.fitting.photo.config import PHOTO_PRESETS, PhotoFitConfig
from roomlight.fitting.photo.fitter import PHOTO_METHODS

_FAST = PHOTO_PRESETS["fast"]
_BALANCED = PHOTO_PRESETS["balanced"]


@click.command("fit-photo")
@click.argument("image", type=click.Path())
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False), help="Output directory.")
@click.option("--depth", type=click.Path(), default=None,
              help="Per-pixel metric depth of IMAGE: .npy, .exr (channel Z) or a 16-bit PNG in millimetres "
                   "[default: the photo case's depth file, else the monocular --estimator].")
@click.option("--depth-kind", type=click.Choice(["z", "radial"]), default=None,
              help="z: distance along the optical axis (depth sensors, MoGe); radial: distance from the camera "
                   "centre [default: z, or the photo case's camera.json].")
@click.option("--mask", type=click.Path(), default=None,
              help="The objects of interest: a binary mask (each connected component is an object) or integer "
                   "labels (each value is an object), IMAGE's size [default: the photo case's mask, else none: "
                   "the light is fitted to the visible room alone].")
@click.option("--normals", type=click.Path(), default=None,
              help="Per-pixel unit normals (.npy or .exr, camera frame: x right, y up, z towards the viewer) "
                   "[default: from the depth mesh].")
@click.option("--fov", type=FINITE, default=None, metavar="DEG", help="Horizontal field of view in degrees.")
@click.option("--intrinsics", default=None, metavar="FX,FY,CX,CY",
              help="Focal lengths and principal point in pixels ((0, 0) = the image's top-left corner).")
@click.option("--pitch", type=FINITE, default=None, metavar="DEG", help="Camera tilt, positive looking up [default: 0].")
@click.option("--roll", type=FINITE, default=None, metavar="DEG", help="Camera roll about its view axis [default: 0].")
@click.option("--estimator", default=None, metavar="moge|MODULE:FUNCTION",
              help="Monocular depth/intrinsics/normals estimator used when there is no depth file "
                   "[default: moge, when installed with its weights].")
@click.option("--method", type=click.Choice(PHOTO_METHODS), default="prior", show_default=True,
              help="prior: the 2.5D light of the prior (paper); prior-envmap: the prior's radiance at infinity; "
                   "direct-envmap: a free env map with a smoothness prior. All fit the materials too.")
@click.option("--compare", multiple=True, type=click.Choice(PHOTO_METHODS), metavar="METHOD",
              help="Also fit METHOD the same way (out/compare/METHOD) and show it in probes.png (repeatable).")
@click.option("--model", type=click.Path(), default=None,
              help="Trained prior for the prior methods: a model folder, a training run or the authors' run "
                   "[default: the prior bundled with roomlight].")
@click.option("--preset", type=click.Choice(["auto", *PHOTO_PRESETS]), default="auto", show_default=True,
              help="auto: fast on a CPU, paper on a GPU (what the renderer runs on); "
                   f"paper: the paper's settings ({PhotoFitConfig.iterations} it, {PhotoFitConfig.spp} spp, "
                   f"{PhotoFitConfig.render_size} px); fast: a few minutes on a laptop CPU ({_FAST.iterations} it, "
                   f"{_FAST.spp} spp, {_FAST.render_size} px); balanced: between them ({_BALANCED.iterations} it, "
                   f"{_BALANCED.spp} spp, {_BALANCED.render_size} px).")
@click.option("--iterations", type=int, default=None, help="Override: optimisation steps.")
@click.option("--spp", type=int, default=None, help="Override: samples per pixel per step.")
@click.option("--seed", type=int, default=None, help=f"Override: base seed {default_of(PhotoFitConfig, 'seed')}.")
@click.option("--init", "init", type=click.Choice(["auto", "view", "samples", "zero"]), default=None,
              help="Start of the prior's latent: view (the prior's view encoder reads the photograph), samples "
                   "(the paper's: the largest of init_samples random rooms), zero (the mean room). "
                   "[default: auto = view when the prior has a view encoder, else samples]")
@click.option("--view-encoder", "view_encoder", type=click.Path(exists=True, file_okay=False), default=None,
              help="Use this view encoder (a folder written by train-view-encoder, e.g. RUN/best) "
                   "instead of the one beside the prior.")
@click.option("--restart", is_flag=True, help="Start over instead of resuming an interrupted fit found in --out.")
@click.option("--set", "sets", multiple=True, metavar="FIELD=VALUE",
              help="Override any photo fit setting (docs/photo.md), e.g. --set render_size=320 (repeatable).")
@click.option("--quiet", is_flag=True, help="No progress bar.")
def command(image, out_dir, depth, depth_kind, mask, normals, fov, intrinsics, pitch, roll, estimator, method, compare,
            model, preset, iterations, spp, seed, init, view_encoder, restart, sets, quiet):
    """Recover the room's light, and the objects' materials, from the photograph IMAGE.

    IMAGE is an 8-bit PNG/JPEG (sRGB) or a linear EXR, or a photo case folder (image, depth,
    mask and camera.json; docs/file-formats.md), whose files the options override.

    \b
    Writes to --out:
      panorama.exr        recovered radiance (R,G,B) + radial depth (Z)
      emitter/            the light as an emitter bundle (PLY + EXR + Mitsuba XML)
      materials.json      each object's albedo, roughness, metallic
      render.png/.exr     the objects re-rendered with their materials under the light
      compare.png         photograph | render | error on the fitted pixels
      probes.png          mirror and diffuse probes on the objects, per light
      result.json         objective, materials, settings, timings (+ history.jsonl, loss.png)
    An interrupted fit resumes from its saved state when the command is run again.
    """
    from roomlight.fitting.photo.case import load_photo
    from roomlight.fitting.photo.config import photo_config
    from roomlight.fitting.photo.pipeline import run_photo

    if preset == "auto":
        from roomlight.core.render.variant import torch_device

        preset = "paper" if torch_device() == "cuda" else "fast"
        click.echo(f"note: --preset auto: {preset} (the renderer runs on the {'GPU' if preset == 'paper' else 'CPU'})",
                   err=True)
    cfg = photo_config(preset, iterations=iterations, spp=spp, seed=seed, init=init, **parse_sets(sets))
    case = load_photo(image, depth=depth, depth_kind=depth_kind, mask=mask, normals=normals, fov=fov,
                      intrinsics=intrinsics, pitch=pitch, roll=roll, estimator=estimator,
                      min_object_fraction=cfg.min_object_fraction)
    for note in case.notes:
        click.echo(f"note: {note}", err=True)
    prior = None
    if any(method_record(m).takes_model_option(model is not None) for m in (method, *compare)):
        prior, _ = load_prior(model, f"--method {method}")
        if view_encoder is not None:
            set_view_encoder(prior, view_encoder)
    click.echo(f"{case.files['image']}: {case.width}x{case.height}, {len(case.objects.ids)} object(s), "
               f"{case.depth_kind} depth from {case.files['depth']}", err=True)
    run_photo(case, method, cfg, out_dir, model=prior, compare=compare, progress=not quiet, resume=not restart,
              say=click.echo)
