"""``roomlight sample``: draw rooms from the prior (EXRs, 2.5D area lights, a figure), or interpolate."""

from __future__ import annotations

import json
from pathlib import Path

import click

from roomlight.cli.common import echo_fixes, parse_sets, repair_options, sets_option


def _encode_file(model, path, fit_steps: int, sets: dict, repairs: dict):
    """Latent (D,) of a panorama file: the encoder's mean, refined by a latent fit if fit_steps > 0."""
    import torch

    from roomlight.prior.data.dataset import load_training_pair
    from roomlight.prior.latent_fit import LatentFitConfig, fit_latent

    device = next(model.parameters()).device
    rad, dep, info = load_training_pair(path, model.config.resolution, calibrate=True,
                                        depth_units=model.metadata.get("depth_units", "metres"), **repairs)
    echo_fixes(info["fixes"])
    with torch.no_grad():
        z = model.encode(rad[None].to(device), dep[None].to(device)).mean
    if fit_steps > 0:
        z = fit_latent(model, rad[None].to(device), dep[None].to(device), LatentFitConfig(steps=fit_steps).override(**sets),
                       z0=z).z
    return z[0].cpu()


@click.command("sample")
@click.option("--model", "model_path", required=True, type=click.Path(),
              help="Model directory, training run (uses RUN/best), the authors' run folder, or a bundled "
                   "model by name: prior (the bundled prior), lite.")
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False))
@click.option("--n", "count", type=int, default=8, show_default=True,
              help="Number of samples (or interpolation steps).")
@click.option("--seed", type=int, default=0, show_default=True)
@click.option("--temperature", type=float, default=1.0, show_default=True, help="Scale of z ~ N(0, t^2 I).")
@click.option("--interpolate", nargs=2, type=click.Path(exists=True, dir_okay=False), default=None,
              metavar="A B", help="Interpolate between panoramas A and B (N steps) instead of sampling.")
@click.option("--mode", type=click.Choice(["slerp", "lerp"]), default="slerp", show_default=True,
              help="Latent interpolation path.")
@click.option("--fit-steps", type=int, default=0, show_default=True,
              help="Refine the encoded latents of A and B with a latent fit of this many steps.")
@click.option("--render/--no-render", default=True, show_default=True,
              help="Render glossy probe spheres lit by each sample's 2.5D area light (Mitsuba).")
@click.option("--render-res", type=int, default=160, show_default=True)
@click.option("--spp", type=int, default=32, show_default=True)
@click.option("--emitters/--no-emitters", default=True, show_default=True,
              help="Write each sample as a 2.5D area light bundle (PLY + EXR + scene.xml).")
@sets_option("LatentFitConfig of --fit-steps")
@repair_options
def command(model_path, out_dir, count, seed, temperature, interpolate, mode, fit_steps, render, render_res, spp,
            emitters, sets, clamp_negative, fill_nonfinite):
    """Decode z ~ N(0, I) into panoramas: EXRs, 2.5D area lights and a figure (paper Fig. 3).

    \b
    Writes to --out:
      sample_000.exr ...   radiance (R,G,B) + depth (Z) at the model's resolution
      sample_000/ ...      each as a 2.5D area light bundle (unless --no-emitters)
      probes_000.exr ...   glossy spheres at three positions lit by it (unless --no-render)
      samples.png          radiance | depth | probes, one row per sample
      latents.json         the latents and settings
    With --interpolate A B: interp_000.exr ... and interpolation.png instead.
    """
    from roomlight.core.emitter.export import export_emitter
    from roomlight.prior.eval.figures import interpolation_strip, samples_figure
    from roomlight.prior.eval.metrics import peak_contrast
    from roomlight.prior.eval.samples import (decode_latents, interpolate_latents, probe_layout, render_probes,
                                        sample_latents)
    from roomlight.core.io import write_exr, write_panorama
    from roomlight.prior.model.runs import load_run_model

    sets = parse_sets(sets)
    repairs = {"clamp_negative": clamp_negative, "fill_nonfinite": fill_nonfinite}
    from roomlight.prior.latent_fit import LatentFitConfig

    LatentFitConfig().override(**sets)  # refuse a bad --set before any work
    model = load_run_model(model_path)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    units = model.metadata.get("depth_units", "metres")
    if interpolate:
        a, b = interpolate
        z = interpolate_latents(_encode_file(model, a, fit_steps, sets, repairs), _encode_file(model, b, fit_steps, sets, repairs), count, mode)
        rad, dep = decode_latents(model, z)
        for i in range(count):
            write_panorama(out / f"interp_{i:03d}.exr", (rad[i], dep[i, 0]), half=False,
                           metadata={"from": str(a), "to": str(b), "t": i / (count - 1), "mode": mode,
                                     "depth_units": units})
        interpolation_strip(out / "interpolation.png", rad, dep)
        (out / "latents.json").write_text(json.dumps({"from": str(a), "to": str(b), "mode": mode,
                                                      "fit_steps": fit_steps, "z": z.tolist()}) + "\n")
        click.echo(f"interpolated {a} -> {b} in {count} steps ({mode}) -> {out / 'interpolation.png'}")
        return

    z = sample_latents(count, model.config.latent_dim, seed, temperature)
    rad, dep = decode_latents(model, z)
    renders = []
    for i in range(count):
        meta = {"seed": seed, "index": i, "temperature": temperature, "depth_units": units, "model": str(model_path)}
        write_panorama(out / f"sample_{i:03d}.exr", (rad[i], dep[i, 0]), half=False, metadata=meta)
        if emitters:
            export_emitter(out / f"sample_{i:03d}", rad[i].permute(1, 2, 0), dep[i, 0], "mesh", metadata=meta)
        if render:
            probes = probe_layout(dep[i, 0])
            img = render_probes(rad[i].permute(1, 2, 0), dep[i, 0], probes, resolution=render_res, spp=spp, seed=i)
            write_exr(out / f"probes_{i:03d}.exr", {"R": img[..., 0].numpy(), "G": img[..., 1].numpy(),
                                                    "B": img[..., 2].numpy()}, half=False)
            renders.append(img)
            click.echo(f"sample {i}: probes at " + ", ".join(
                f"({c[0]:.2f}, {c[1]:.2f}, {c[2]:.2f}) r={r:.2f}" for c, r in probes), err=True)
    samples_figure(out / "samples.png", rad, dep, renders or None,
                   title=f"{count} samples of {model_path} (seed {seed}, temperature {temperature:g})")
    contrast = peak_contrast(rad)
    (out / "latents.json").write_text(json.dumps({"seed": seed, "temperature": temperature, "z": z.tolist(),
                                                  "peak_contrast": contrast.tolist()}) + "\n")
    # quantile(0.5), not median(): torch takes the lower middle value of an even count.
    click.echo(f"brightest pixel / median luminance: median {float(contrast.double().quantile(0.5)):.1f}x "
               f"(range {contrast.min():.1f}-{contrast.max():.1f}x)")
    click.echo(f"{count} samples -> {out} (figure: {out / 'samples.png'})")
