"""``roomlight experiment``: the paper's analyses, one command each (docs/experiments.md)."""

from __future__ import annotations

from pathlib import Path

import click

from roomlight.cli.common import RoomlightGroup, default_of, fail, parse_sets
from roomlight.evaluation.experiments.capacity import CapacityConfig as _Cap


def _sets(what: str, example: str):
    return click.option("--set", "sets", multiple=True, metavar="FIELD=VALUE",
                        help=f"Override any {what} field (repeatable; docs/experiments.md), e.g. --set {example}.")


def _csv(value):
    if value is None:
        return None
    items = tuple(s.strip() for s in str(value).split(",") if s.strip())
    return items or None


@click.group("experiment", cls=RoomlightGroup)
def command():
    """The paper's supplementary analyses, each resumable and seeded.

    \b
      roomlight experiment capacity --out DIR [--rooms N]   2.5D light vs env map vs a path-traced room
      roomlight experiment ablate --out DIR                 the six-row ablation table (trains six priors)
      roomlight experiment cost --out DIR [--quick]         parameters, throughput, decode and fit times
    """


@command.command("capacity")
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False),
              help="Folder for the tables, figures and per-room renders; rerunning continues it.")
@click.option("--rooms", type=click.IntRange(min=1), default=None,
              help="Procedural rooms to measure (rooms without space for the probes are skipped) "
                   f"{default_of(_Cap, 'rooms')}.")
@click.option("--seed", type=int, default=None,
              help=f"First room seed; renders are seeded from it {default_of(_Cap, 'seed')}.")
@click.option("--pano-res", "pano_height", type=click.IntRange(min=4), default=None,
              help=f"Panorama / emitter height H, width 2H (the paper's: 128) {default_of(_Cap, 'pano_height')}.")
@click.option("--pano-spp", type=click.IntRange(min=1), default=None,
              help=f"Samples per pixel of the panoramas, a perfect square {default_of(_Cap, 'pano_spp')}.")
@click.option("--image-size", type=click.IntRange(min=4), default=None,
              help=f"Probe images are N x N pixels {default_of(_Cap, 'image_size')}.")
@click.option("--spp", type=click.IntRange(min=1), default=None,
              help=f"Samples per pixel of every probe render, ground truth and emitters {default_of(_Cap, 'gt_spp')}.")
@click.option("--materials", default=None,
              help=f"Comma-separated probe materials [default: {','.join(_Cap.materials)}].")
@click.option("--wall-light-room", is_flag=True,
              help="Measure the fixed test room instead: probes next to a wall light (the near-field case).")
@_sets("CapacityConfig", "probe_radius=0.1")
@click.option("--quiet", is_flag=True, help="No progress bar.")
def capacity(out_dir, rooms, seed, pano_height, pano_spp, image_size, spp, materials, wall_light_room, sets, quiet):
    """Capacity of a single 2.5D area light (supplementary table): probe spheres in procedural
    rooms, path traced in the full room and relit by a 2.5D light, an environment map and a
    sphere proxy built from the exact panorama at three capture points.

    Writes OUT/capacity.md (the paper's table for one room and aggregated over the rooms with
    bootstrap intervals, the ratio environment map / 2.5D light and a verdict on the paper's
    2-5x), OUT/capacity.json and OUT/figures/*.png. Finished rooms are skipped on a rerun.
    """
    from roomlight.evaluation.experiments.capacity import CapacityConfig, run_capacity

    changes = {k: v for k, v in dict(rooms=rooms, seed=seed, pano_height=pano_height, pano_spp=pano_spp,
                                     image_size=image_size, gt_spp=spp, emitter_spp=spp,
                                     materials=_csv(materials)).items() if v is not None}
    changes.update(parse_sets(sets))
    cfg = CapacityConfig().override(**changes)
    room_list = None
    if wall_light_room:
        from roomlight.evaluation.experiments.layout import Caster, wall_light_layout, wall_light_room as make
        from roomlight.datagen.synth.scene import build_scene

        room = make()
        layout = wall_light_layout(room, Caster(build_scene(room)), cfg.layout_config())
        room_list = [("wall-light", room, layout)]
    summary = run_capacity(out_dir, cfg, rooms=room_list, progress=not quiet)
    click.echo(summary["markdown"])
    click.echo(f"-> {Path(out_dir) / 'capacity.md'}")


@command.command("ablate")
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False),
              help="Study folder (data, six training runs, benchmark, tables); rerunning continues it.")
@click.option("--preset", "study", type=click.Choice(["cpu", "paper", "tiny"]), default="cpu", show_default=True,
              help="Size of the study. cpu: lite network, 1000 steps a row (about 2 h on 2 cores); paper: the "
                   "paper's network and schedule (a GPU); tiny: a smoke test of about a minute. The network "
                   "itself is --set preset=NAME (a roomlight train --config).")
@click.option("--data", "data_dir", type=click.Path(exists=True, file_okay=False), default=None,
              help="Panorama folder with train/ val/ test/ (roomlight synth); default: render rooms into OUT/data.")
@click.option("--steps", type=click.IntRange(min=0), default=None, help="Optimiser steps per row (0: the preset's epochs).")
@click.option("--rows", default=None,
              help="Comma-separated rows [default: full,no-peak,no-gradient,no-adagn,no-latitude,none].")
@click.option("--seed", type=int, default=None, help="Seed of weights, data order, rooms and placements.")
@_sets("AblationConfig", "fit_steps=1500")
@click.option("--quiet", is_flag=True, help="No progress bars.")
def ablate(out_dir, study, data_dir, steps, rows, seed, sets, quiet):
    """The ablation table: the full prior and five ablations (w/o peak loss, w/o gradient terms,
    w/o AdaGN, w/o latitude channels, all four removed), trained with one equal budget, scored on
    latent fitting and on silver-matte inverse rendering.

    Every stage is resumable: a finished training run or evaluation is skipped on a rerun, an
    interrupted training continues from its last checkpoint.
    """
    from roomlight.evaluation.experiments.ablation import ABLATION_PRESETS, run_ablation

    changes = {k: v for k, v in dict(steps=steps, rows=_csv(rows), seed=seed).items() if v is not None}
    changes.update(parse_sets(sets))
    cfg = ABLATION_PRESETS[study].override(**changes)
    try:
        summary = run_ablation(out_dir, cfg, data=data_dir, progress=not quiet,
                               note=lambda m: click.echo(m, err=True))
    except KeyboardInterrupt:
        fail(f"interrupted; run the same command again to continue {out_dir}")
    click.echo(summary["markdown"])
    click.echo(f"-> {Path(out_dir) / 'ablation.md'}")


@command.command("cost")
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False), help="Folder for cost.md / .json.")
@click.option("--quick", is_flag=True, help="Fewer repeats and a small fit (under a minute): a smoke test.")
@click.option("--paper", is_flag=True,
              help="The paper's settings: training batch 32, fits of 1000x1000 images at 64 spp (slow on a CPU).")
@click.option("--model-preset", default=None, help="Network to measure [default: default, the paper's].")
@click.option("--device", type=click.Choice(["auto", "cpu", "cuda"]), default="auto", show_default=True,
              help="auto: the GPU when one is usable.")
@click.option("--methods", default=None, help="Comma-separated fitting methods [default: all].")
@_sets("CostConfig", "train_batch=32")
def cost(out_dir, quick, paper, model_preset, device, methods, sets):
    """The cost table on this machine: parameters, training throughput (and the paper's schedule
    in hours at that rate), decode time at the model's resolution, fit time per case for each
    method, with the device named."""
    from roomlight.evaluation.experiments.cost import COST_PRESETS, run_cost

    if quick and paper:
        fail("--quick and --paper exclude each other")
    cfg = COST_PRESETS["quick" if quick else "paper" if paper else "default"]
    changes = {k: v for k, v in dict(model_preset=model_preset, methods=_csv(methods)).items() if v is not None}
    changes.update(parse_sets(sets))
    cfg = cfg.override(**changes)
    summary = run_cost(out_dir, cfg, device=device)
    click.echo(summary["markdown"])
    click.echo(f"-> {Path(out_dir) / 'cost.md'}")
