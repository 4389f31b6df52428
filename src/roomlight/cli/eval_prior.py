"""``roomlight eval-prior``: score the prior's encoder pass and latent fits on a panorama folder."""

from __future__ import annotations

from pathlib import Path

import click

from roomlight.cli.common import fail, parse_sets, repair_options, sets_option


@click.command("eval-prior")
@click.option("--model", "model_path", required=True, type=click.Path(),
              help="Model directory, training run (uses RUN/best), the authors' run folder, or a bundled model "
                   "by name (prior, lite, veni, veni-d).")
@click.option("--data", "data_dir", required=True, type=click.Path(exists=True, file_okay=False),
              help="Folder of panoramas with depth, or without it with --radiance-only (a test/ sub-folder "
                   "is used when present).")
@click.option("--split", type=click.Choice(["auto", "train", "val", "test", "all"]), default="auto", show_default=True,
              help="auto: test/ if the folder has one, else every file.")
@click.option("--fit-steps", type=int, default=1500, show_default=True,
              help="Latent-fit iterations; 0 skips the fit row.")
@click.option("--fit-init", type=click.Choice(["zero", "encoder"]), default="zero", show_default=True,
              help="Latent fit starts from z = 0 (the paper's protocol) or the encoder's posterior mean.")
@click.option("--depth-weight", type=float, default=1.0, show_default=True,
              help="Latent fit: weight of the depth channel against each radiance channel (1: the paper's "
                   "protocol).")
@click.option("--peak-weight", type=float, default=0.0, show_default=True,
              help="Latent fit: weight of a log-L1 term over the brightest 0.5 % of pixels (0: the paper's "
                   "protocol).")
@click.option("--depth-only", is_flag=True, help="Add a depth-only latent-fit row.")
@click.option("--pixel-level", is_flag=True,
              help="Add the pixel-level rows (paper Tab. 1, 'Smooth. HDR' / 'Smooth. HDRD'): a free panorama fitted "
                   "with the latent fit's settings and the smoothness prior (no bottleneck).")
@click.option("--pixel-smoothness", type=float, default=None,
              help="Smoothness weight of the pixel-level rows, per channel and pixel [default: 0.05].")
@click.option("--limit", type=int, default=None, help="Evaluate at most this many panoramas.")
@click.option("--radiance-only", is_flag=True,
              help="Panoramas without depth (real captures, .exr or .hdr): fit z to radiance alone and "
                   "score radiance only (no encoder row: the encoder needs depth).")
@click.option("--batch-size", type=int, default=8, show_default=True)
@click.option("--out", "out_dir", type=click.Path(file_okay=False), default=None,
              help="Where eval_prior.md / .json go (default: the --model folder).")
@repair_options
@sets_option("LatentFitConfig of the latent-fit rows")
def command(model_path, data_dir, split, fit_steps, fit_init, depth_weight, peak_weight, depth_only, pixel_level,
            pixel_smoothness, radiance_only, limit, batch_size, out_dir, clamp_negative, fill_nonfinite, sets):
    """Reconstruction quality of the prior (paper Tab. 1): encoder pass and latent fit (and, with
    --pixel-level, the smoothness prior's pixel-level reference rows). Works for the panoramic VAE and
    for VENI / VENI+D (a radiance-only VENI is fitted to radiance and has no AbsRel).

    Metrics: PSNR and SSIM on tone-mapped LDR (LPIPS too when its weights are available
    locally), PSNR on HDR, AbsRel on depth. Prints a Markdown table and writes it with a JSON
    file holding per-image values.
    """
    from roomlight.prior.data import PanoramaDataset, split_files
    from roomlight.prior.data.splits import find_panoramas, has_split_folders
    from roomlight.prior.eval.prior import evaluate_prior, report_markdown, write_report
    from roomlight.prior.latent_fit import LatentFitConfig
    from roomlight.prior.model.runs import load_run_model, resolve_run_model

    model = load_run_model(model_path)
    if split == "auto":
        files = split_files(data_dir)["test"] if has_split_folders(data_dir) else []
        files = files or find_panoramas(data_dir)
    elif split == "all":
        files = find_panoramas(data_dir)
    else:
        files = split_files(data_dir)[split]
    files = files[:limit] if limit else files
    units = model.metadata.get("depth_units", "metres")
    ds = PanoramaDataset(files, model.config.resolution, root=data_dir, calibrate=True, depth_units=units,
                         clamp_negative=clamp_negative, fill_nonfinite=fill_nonfinite,
                         require_depth=not radiance_only)
    fit = None
    if fit_steps > 0:
        fit = LatentFitConfig(steps=fit_steps, init_from_encoder=fit_init == "encoder", depth_weight=depth_weight,
                              peak_weight=peak_weight).override(**parse_sets(sets))
    if pixel_smoothness is not None and not pixel_level:
        raise click.UsageError("--pixel-smoothness sets the weight of the --pixel-level rows: add --pixel-level")
    if pixel_level and fit is None:
        raise click.UsageError("--pixel-level uses the latent fit's settings: give --fit-steps > 0")
    from roomlight.prior.latent_fit.pixel import DEFAULT_SMOOTHNESS

    smooth = (DEFAULT_SMOOTHNESS if pixel_smoothness is None else pixel_smoothness) if pixel_level else None
    report = evaluate_prior(model, ds, fit, batch_size=batch_size, depth_only_fit=depth_only,
                            note=lambda m: click.echo(m, err=True), radiance_only=radiance_only,
                            pixel_smoothness=smooth)
    if report["count"] == 0:
        no_depth = report["skipped"] and all("no depth" in s["reason"] for s in report["skipped"])
        fail(f"no usable panorama in {data_dir}"
             + ("; its files have no depth: evaluate them with --radiance-only" if no_depth else ""))
    report.update({"model": str(resolve_run_model(model_path)), "data": str(data_dir), "split": split})
    # the default is beside the model, except for a bundled one (not the package's own folder)
    out = Path(out_dir) if out_dir else (Path(model_path) if Path(model_path).exists() else
                                         Path(f"eval-prior-{model_path}"))
    if out.is_file():
        out = out.parent
    md, js = write_report(report, out)
    click.echo(report_markdown(report))
    click.echo(f"-> {md}, {js}")
