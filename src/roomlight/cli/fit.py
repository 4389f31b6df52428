"""``roomlight fit``: recover a scene's illumination from an image of known objects."""

from __future__ import annotations

import click

from roomlight.cli.common import default_of, load_prior, parse_sets
from roomlight.fitting.inverse.config import FIT_PRESETS, FitConfig
from roomlight.fitting.inverse.methods import METHODS
from roomlight.fitting.methods import method as method_record

_FAST = FIT_PRESETS["fast"]


@click.command("fit")
@click.argument("scene", type=click.Path())
@click.option("--method", type=click.Choice(METHODS), default="prior", show_default=True,
              help="prior: the 2.5D prior (paper); prior-envmap: the prior shown at infinity; veni / veni-d: "
                   "the VENI prior at infinity / VENI+D as a 2.5D light (their bundled models, or --model, or "
                   "--set veni_model=PATH / veni_d_model=PATH); direct-al / direct-sphere / direct-envmap: "
                   "per-pixel maps with a smoothness prior.")
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False), help="Output directory.")
@click.option("--model", type=click.Path(), default=None,
              help="Trained prior for the prior methods: a model folder, a training run (uses its best/), "
                   "the authors' run folder or a bundled model's name [default: the prior bundled with roomlight].")
@click.option("--preset", type=click.Choice(list(FIT_PRESETS)), default="paper", show_default=True,
              help=f"paper: the paper's settings ({FitConfig.iterations} it, {FitConfig.spp} spp); fast: a CPU-friendly "
                   f"setting ({_FAST.iterations} it, {_FAST.spp} spp).")
@click.option("--iterations", type=int, default=None, help="Override: optimisation steps.")
@click.option("--spp", type=int, default=None, help="Override: samples per pixel per step.")
@click.option("--lr", type=float, default=None, help="Override: Adam learning rate.")
@click.option("--seed", type=int, default=None, help="Override: base seed.")
@click.option("--view", default=None, help=f"Scene view to fit {default_of(FitConfig, 'view')}.")
@click.option("--image", type=click.Choice(["ldr", "hdr"]), default=None,
              help=f"Fit the 8-bit recording (ldr) or the linear EXR (hdr) {default_of(FitConfig, 'image')}.")
@click.option("--margin", type=float, default=None, help=f"Repulsion margin in metres {default_of(FitConfig, 'margin')}.")
@click.option("--lambda-rep", type=float, default=None, help=f"Repulsion weight {default_of(FitConfig, 'lambda_rep')}.")
@click.option("--lambda-log", type=float, default=None, help=f"Log-term weight {default_of(FitConfig, 'lambda_log')}.")
@click.option("--z-prior", type=float, default=None, help="Gaussian prior weight on the latent (real photos).")
@click.option("--fit-depth-scale", is_flag=True, default=None, help="Also fit a global scale of the decoded depth.")
@click.option("--pixel-subset", type=float, default=None, help="Fraction of object pixels in the loss per step.")
@click.option("--whole-frame", "crop_to_mask", flag_value=False, default=None,
              help="Render every pixel each step (default: only the mask's bounding box, which the loss sees).")
@click.option("--set", "sets", multiple=True, metavar="FIELD=VALUE",
              help="Override any fit setting (docs/inverse-rendering.md), e.g. --set eval_every=5 (repeatable).")
@click.option("--quiet", is_flag=True, help="No progress bar.")
def command(scene, method, out_dir, model, preset, sets, quiet, **overrides):
    """Fit the illumination of SCENE (a scene.json/.yaml or its directory) with --method.

    Writes to --out: panorama.exr (recovered radiance + depth), emitter/ (PLY + Mitsuba XML),
    history.jsonl (one line per iteration), loss.png, preview.png (target | render | error) and
    result.json.
    """
    from pathlib import Path

    from roomlight.fitting.inverse import fit_config, fit_scene
    from roomlight.fitting.inverse.outputs import recorded_light_note
    from roomlight.fitting.scene import load_scene

    spec = load_scene(scene)
    cfg = fit_config(preset, **{**overrides, **parse_sets(sets)})
    prior = None
    if method_record(method).takes_model_option(model is not None):
        prior, _ = load_prior(model, f"--method {method}")  # VENI methods: --model, else --set veni_model=...
    result = fit_scene(spec, method, cfg, out_dir=out_dir, model=prior, progress=not quiet)
    click.echo(f"{method}: best iteration {result.best_iteration} (fixed-seed loss {result.best_loss:.4g}) "
               f"in {result.seconds:.1f} s -> {out_dir}")
    if result.nonfinite_steps:
        click.echo(f"note: {result.nonfinite_steps} step(s) had a non-finite loss or gradient and were skipped", err=True)
    note = recorded_light_note(Path(out_dir) / "result.json")
    if note:
        click.echo(note, err=True)
