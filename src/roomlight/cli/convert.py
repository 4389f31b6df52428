"""``roomlight convert``: the paper authors' run folder -> a roomlight checkpoint (no pickle)."""

from __future__ import annotations

import click


@click.command("convert")
@click.argument("run_dir", type=click.Path(exists=True))
@click.argument("out_dir", type=click.Path(file_okay=False))
def command(run_dir, out_dir):
    """Convert the authors' RUN_DIR (config.yaml + last_epoch.pth) into OUT_DIR.

    OUT_DIR gets model.safetensors + config.json, with the authors' normalisation and
    depth_units = "scale-free" recorded, loadable with `--model OUT_DIR` everywhere.
    The .pth is a third-party pickle: it is read with torch.load(weights_only=True).
    """
    import warnings

    from roomlight.prior.model import ThirdPartyCheckpointWarning, convert_authors_checkpoint

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ThirdPartyCheckpointWarning)
        out = convert_authors_checkpoint(run_dir, out_dir)
    for w in caught:
        click.echo(f"note: {w.message}", err=True)
    click.echo(f"converted {run_dir} -> {out} (model.safetensors + config.json)")
