"""``roomlight train-view-encoder``: train the photo fit's amortized start for a prior (resumable)."""

from __future__ import annotations

import json

import click

from roomlight.cli.common import load_prior, parse_sets


@click.command("train-view-encoder")
@click.option("--data", "data_dir", required=True, type=click.Path(exists=True, file_okay=False),
              help="Panorama folder with train/ and val/ (what `roomlight synth` writes); views are cut from it.")
@click.option("--out", "run_dir", required=True, type=click.Path(file_okay=False),
              help="Run folder; if it holds checkpoints, training continues from the newest.")
@click.option("--model", default=None, metavar="MODEL",
              help="The prior the encoder is for (model folder or training run; default: the bundled one). "
                   "Its weights stay frozen.")
@click.option("--max-steps", type=click.IntRange(min=1), default=None, help="Length of the schedule (default 6000).")
@click.option("--batch-size", type=click.IntRange(min=1), default=None, help="Views per step (default 32).")
@click.option("--lr", type=float, default=None, help="Peak learning rate (default 3e-4).")
@click.option("--seed", type=int, default=None)
@click.option("--limit", type=click.IntRange(min=1), default=None, help="Use only the first N training panoramas.")
@click.option("--time-budget", type=click.FloatRange(min=0, min_open=True), default=None, metavar="MINUTES",
              help="Stop after this many minutes (validation and a checkpoint follow); the same command continues.")
@click.option("--until-step", type=click.IntRange(min=1), default=None, help="Stop at this step (checkpointed).")
@click.option("--set", "sets", multiple=True, metavar="FIELD=VALUE",
              help="Override a setting (docs/photo.md), e.g. --set fov_deg=[30,90] --set latent_weight=2.")
@click.option("--print-config", is_flag=True, help="Print the resolved settings as JSON and exit.")
def command(data_dir, run_dir, model, max_steps, batch_size, lr, seed, limit, time_budget, until_step, sets,
            print_config):
    """Train a view encoder: what a photograph shows -> the prior's latent and exposure.

    Training views are perspective crops of the panoramas in --data (random field of view, pitch,
    roll and yaw, exposed and clipped like a photograph, with random objects hiding the room),
    lifted onto the sphere around the camera. The loss is the prior's reconstruction of the *whole*
    panorama through its frozen decoder, plus the distance to the whole panorama's encoder mean.

    Interrupting (Ctrl-C, SIGTERM) saves a checkpoint; the same command continues exactly. The
    result is RUN/best; copy it into the prior's folder as view_encoder/ (or pass
    --view-encoder RUN/best to fit-photo) so that `fit-photo --init view` uses it.
    """
    from roomlight.prior.viewenc.config import ViewTrainConfig
    from roomlight.prior.viewenc.trainer import ViewEncoderTrainer

    overrides = {k: v for k, v in dict(max_steps=max_steps, batch_size=batch_size, lr=lr, seed=seed).items()
                 if v is not None}
    overrides.update(parse_sets(sets))
    cfg = ViewTrainConfig().replace(**overrides)
    if print_config:
        click.echo(json.dumps(cfg.to_dict(), indent=2))
        return
    prior, prior_path = load_prior(model, "train-view-encoder")
    prior = prior.to("cpu")
    trainer = ViewEncoderTrainer(cfg, prior, data_dir, run_dir, prior_path=prior_path,
                                 note=lambda m: click.echo(m, err=True), limit=limit)
    try:
        summary = trainer.fit(time_budget_s=None if time_budget is None else 60.0 * time_budget, until=until_step)
    except KeyboardInterrupt as exc:
        raise SystemExit(128 + getattr(exc, "signum", 2)) from None
    best = summary["best"]
    click.echo(f"trained to step {summary['step']}/{summary['max_steps']}; best validation loss "
               f"{best if best is None else round(best, 5)}; view encoder: {run_dir}/best")
