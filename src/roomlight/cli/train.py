"""``roomlight train``: train the prior on a folder of panoramas (resumable; torchrun for DDP)."""

from __future__ import annotations

import json

import click

from roomlight.cli.common import parse_sets, repair_options
from roomlight.prior.train.config import TRAIN_PRESETS


@click.command("train")
@click.option("--data", "data_dir", required=True, type=click.Path(exists=True, file_okay=False),
              help="Folder of panorama EXRs (R,G,B,Z or the authors' R,G,B,A), optionally with train/ val/ test/.")
@click.option("--out", "run_dir", required=True, type=click.Path(file_okay=False),
              help="Run folder; if it holds checkpoints, training continues from the newest.")
@click.option("--config", "preset", default="default", show_default=True,
              type=click.Choice(list(TRAIN_PRESETS)), help="Training + model preset.")
@click.option("--batch-size", type=int, default=None, help="Global batch size (over all processes).")
@click.option("--epochs", type=int, default=None)
@click.option("--max-steps", type=int, default=None, help="Train exactly this many steps instead of --epochs.")
@click.option("--lr", type=float, default=None, help="Peak learning rate.")
@click.option("--seed", type=int, default=None)
@click.option("--workers", "num_workers", type=int, default=None, help="Data-loader processes.")
@click.option("--no-cache", is_flag=True, help="Decode EXRs every epoch instead of using the packed cache.")
@click.option("--device", type=click.Choice(["cpu", "cuda"]), default=None, help="Default: cuda when available.")
@click.option("--set", "sets", multiple=True, metavar="FIELD=VALUE",
              help="Override any TrainConfig field (docs/training.md), e.g. --set aug_tilt_deg=0 --set loss.peak=0.")
@click.option("--time-budget", "time_budget", type=click.FloatRange(min=0, min_open=True), default=None,
              metavar="MINUTES", help="Stop after this many minutes of training (validation and a checkpoint "
              "follow); the same command continues later. The schedule is unchanged.")
@click.option("--until-step", type=click.IntRange(min=1), default=None,
              help="Stop at this step (checkpointed); the same command continues later.")
@click.option("--init-from", "init_from", default=None, metavar="MODEL",
              help="Start from this model's weights (a model folder or a run; same --config preset) with a "
              "fresh optimiser and schedule: fine-tuning, or a second schedule after a finished run.")
@click.option("--print-config", is_flag=True, help="Print the resolved configuration as JSON and exit.")
@repair_options
def command(data_dir, run_dir, preset, batch_size, epochs, max_steps, lr, seed, num_workers, no_cache, device,
            sets, time_budget, until_step, init_from, print_config, clamp_negative, fill_nonfinite):
    """Train the illumination prior on panoramas in --data, writing the run to --out.

    Interrupting (Ctrl-C or SIGTERM) finishes the current step and saves a checkpoint; running the
    same command again continues exactly where it stopped, as if it had not been interrupted. Resuming with settings that change the optimisation is refused and the
    differing fields are named. Several GPUs:

    \b
      torchrun --nproc-per-node=4 -m roomlight.cli.main train --data D --out RUN
    """
    from roomlight.prior.train import Trainer, get_train_preset

    overrides = {k: v for k, v in dict(batch_size=batch_size, epochs=epochs, max_steps=max_steps, lr=lr, seed=seed,
                                       num_workers=num_workers).items() if v is not None}
    if init_from is not None:
        overrides["init_from"] = init_from
    if no_cache:
        overrides["cache"] = False
    if clamp_negative:
        overrides["clamp_negative"] = True
    if fill_nonfinite is not None:
        overrides["fill_nonfinite"] = fill_nonfinite
    overrides.update(parse_sets(sets))
    cfg = get_train_preset(preset).replace(**overrides)
    if print_config:
        click.echo(json.dumps(cfg.to_dict(), indent=2))
        return
    trainer = Trainer(cfg, data_dir, run_dir, device=device)
    try:
        summary = trainer.fit(until=until_step, time_budget_s=None if time_budget is None else 60.0 * time_budget)
    except KeyboardInterrupt as exc:  # a checkpoint of the last complete step was written
        raise SystemExit(128 + getattr(exc, "signum", 2)) from None
    finally:
        trainer.close()
    if trainer.dist.is_main:
        best = summary["best"]
        click.echo(f"trained to step {summary['step']}/{summary['total_steps']}; "
                   f"best validation loss {best if best is None else round(best, 5)}; "
                   f"model: {run_dir}/best (use --model {run_dir})")
