"""``roomlight fit-pano``: find the latent whose decoding best matches a panorama."""

from __future__ import annotations

import json
from pathlib import Path

import click

from roomlight.cli.common import echo_fixes, fail, parse_sets, repair_options, sets_option


@click.command("fit-pano")
@click.option("--model", "model_path", required=True, type=click.Path(),
              help="Model directory, training run (uses RUN/best), the authors' run folder, or a bundled "
                   "model by name: prior (the bundled prior), lite.")
@click.argument("pano", type=click.Path(exists=True, dir_okay=False))
@click.option("--depth", "depth_path", type=click.Path(exists=True, dir_okay=False), default=None,
              help="Separate depth file when PANO has no depth channel.")
@click.option("--target", type=click.Choice(["both", "radiance", "depth"]), default=None,
              help="Channels to fit (default: both when PANO has depth, else radiance).")
@click.option("--steps", type=int, default=1500, show_default=True)
@click.option("--lr", type=float, default=0.1, show_default=True)
@click.option("--lr-final", type=float, default=0.01, show_default=True, help="Learning rate after --steps.")
@click.option("--init", type=click.Choice(["zero", "encoder"]), default="zero", show_default=True,
              help="Start from z = 0 (the paper's protocol) or the encoder's posterior mean.")
@click.option("--depth-weight", type=float, default=1.0, show_default=True,
              help="Weight of the depth channel against each radiance channel (1: the paper's protocol).")
@click.option("--peak-weight", type=float, default=0.0, show_default=True,
              help="Weight of a log-L1 term over the brightest 0.5 % of pixels, which keeps the light "
                   "sources' intensity (0: the paper's protocol).")
@click.option("--out", "out_dir", type=click.Path(file_okay=False), default=None,
              help="Output folder (default: PANO's name + '-fit' next to it).")
@click.option("--emitter/--no-emitter", default=True, show_default=True,
              help="Also write the fitted panorama as a 2.5D area light bundle (out/emitter).")
@repair_options
@sets_option("LatentFitConfig (docs/training.md)")
def command(model_path, pano, depth_path, target, steps, lr, lr_final, init, depth_weight, peak_weight, out_dir, emitter, clamp_negative,
            fill_nonfinite, sets):
    """Fit the prior's latent to panorama PANO (decoder frozen; Adam, lr 0.1 -> 0.01).

    \b
    Writes to --out:
      fit.exr          decoded radiance (R,G,B) + depth (Z) at the model's resolution
      target.exr       the target as the model sees it (resampled, exposure calibrated)
      latent.json      z, the objective, the settings and the metrics
      comparison.png   target above fit (tone-mapped radiance | depth)
      emitter/         the fit as a 2.5D area light (PLY + EXR + Mitsuba XML), unless --no-emitter
    """
    from roomlight.core.progress import progress_bar

    from roomlight.prior.data.dataset import load_training_pair
    from roomlight.core.emitter.export import export_emitter
    from roomlight.prior.eval.prior import panorama_metrics
    from roomlight.prior.latent_fit import LatentFitConfig, fit_latent
    from roomlight.core.io import save_png, write_panorama
    from roomlight.prior.model.runs import load_run_model
    from roomlight.prior.eval.panels import training_panel

    model = load_run_model(model_path)
    device = next(model.parameters()).device
    units = model.metadata.get("depth_units", "metres")
    rad, dep, info = load_training_pair(pano, model.config.resolution, calibrate=True, depth_units=units,
                                        depth_path=depth_path, require_depth=False, clamp_negative=clamp_negative,
                                        fill_nonfinite=fill_nonfinite)
    echo_fixes(info["fixes"])
    if target is None:
        target = "both" if dep is not None else "radiance"
    if target != "radiance" and dep is None:
        fail(f"{pano}: --target {target} needs depth; pass --depth FILE or use --target radiance")
    if target != "both" and depth_weight != 1.0:
        fail(f"--depth-weight weighs depth against radiance: it needs --target both (got {target})")
    cfg = LatentFitConfig(steps=steps, lr=lr, lr_final=lr_final, target=target, init_from_encoder=init == "encoder",
                          depth_weight=depth_weight, peak_weight=peak_weight).override(**parse_sets(sets))
    steps = cfg.steps
    rad_b = rad[None].to(device)
    dep_b = dep[None].to(device) if dep is not None else None
    bar = progress_bar(total=steps, desc="fit-pano", unit="step")

    def progress(step, loss):
        bar.update(1)
        if step % 25 == 0:
            bar.set_postfix(loss=f"{loss:.5f}")

    res = fit_latent(model, rad_b if target != "depth" else None, dep_b if target != "radiance" else None, cfg,
                     callback=progress)
    bar.close()
    out = Path(out_dir) if out_dir else Path(pano).with_name(Path(pano).stem + "-fit")
    out.mkdir(parents=True, exist_ok=True)
    fit_rad, fit_dep = res.radiance[0].cpu(), res.depth[0].cpu()
    meta = {"source": str(pano), "model": str(model_path), "exposure_factor": info["exposure_factor"],
            "depth_units": units, "depth_scale": info["depth_scale"]}
    write_panorama(out / "fit.exr", (fit_rad, fit_dep[0]), half=False, metadata={**meta, "fit_target": target})
    write_panorama(out / "target.exr", (rad, dep[0] if dep is not None else None), half=False, metadata=meta)
    metrics = {}
    if dep is not None:
        m = panorama_metrics(fit_rad[None], fit_dep[None], rad[None], dep[None])
        metrics = {k: float(v[0]) for k, v in m.items()}
    record = {"z": res.z[0].tolist(), "objective": float(res.loss[0]), "fit": cfg.to_dict(), "metrics": metrics,
              "history": res.history, **meta}
    (out / "latent.json").write_text(json.dumps(record, indent=2) + "\n")
    shown_dep = dep if dep is not None else fit_dep
    save_png(out / "comparison.png", training_panel((rad[None], shown_dep[None]), (fit_rad[None], fit_dep[None])))
    if emitter:
        export_emitter(out / "emitter", fit_rad.permute(1, 2, 0), fit_dep[0], "mesh",
                       metadata={"source": f"latent fit of {pano}", "depth_units": units})
    summary = ", ".join(f"{k} {v:.4g}" for k, v in metrics.items())
    click.echo(f"fitted {pano} ({target}, {steps} steps): objective {float(res.loss[0]):.5f}"
               + (f"; {summary}" if summary else "") + f" -> {out}")
