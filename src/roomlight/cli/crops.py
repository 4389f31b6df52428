"""``roomlight bench make-crops | run-crops | report-crops``: the field's three-sphere protocol."""

from __future__ import annotations

from pathlib import Path

import click

from roomlight.cli.common import echo_run_summary, load_prior
from roomlight.fitting.methods import CROPS, check_methods, methods_for


def _csv(text):
    return [t.strip() for t in text.split(",") if t.strip()] if text else []


@click.command("make-crops")
@click.argument("panoramas", nargs=-1, required=True, type=click.Path(exists=True))
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False), help="Crop set folder.")
@click.option("--set-name", default="", help="A name for where the panoramas come from, recorded with each crop.")
@click.option("--quiet", is_flag=True, help="No progress bar.")
def make_crops(panoramas, out_dir, set_name, quiet):
    """Cut the protocol's input crop out of each of PANORAMAS (EXR files or folders of them).

    Each panorama is tone-mapped (gamma 2.4, its 99th percentile of non-zero values at 0.9, clipped) and
    viewed from its centre towards the middle of the image: 60 degrees vertical, 4:3, 256x192 (crop.png);
    the panorama itself is kept at 128x256 as the truth (truth.exr). Existing crops are kept.
    """
    from roomlight.evaluation.crops.bench import make_crop_set

    files = []
    for p in map(Path, panoramas):
        files += sorted(p.rglob("*.exr")) if p.is_dir() else [p]
    names = make_crop_set(files, out_dir, set_name, progress=not quiet)
    click.echo(f"make-crops: {len(names)} crops in {out_dir}")


@click.command("run-crops")
@click.argument("crops", type=click.Path(exists=True, file_okay=False))
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False), help="Results folder.")
@click.option("--methods", default=None,
              help=f"Comma-separated methods [default: {','.join(methods_for(CROPS))}].")
@click.option("--model", type=click.Path(), default=None, help="The prior [default: the bundled prior].")
@click.option("--spp", type=int, default=256, show_default=True,
              help="Samples per pixel of the sphere renders (the truth's: twice as many).")
@click.option("--shard", default=None, metavar="I/N", help="Run only cases I, I+N, I+2N, ... (0 <= I < N).")
@click.option("--quiet", is_flag=True, help="No progress bar.")
def run_crops(crops, out_dir, methods, model, spp, shard, quiet):
    """Give each crop of CROPS to each method and score its panorama by the three spheres.

    Each case writes OUT/cases/<crop>/<method>/: pred.exr (the method's panorama), spheres.png (its three
    spheres beside the truth's) and result.json (si-RMSE, RMSE, angular error and normalised RMSE per
    sphere). Finished cases are skipped, so re-running resumes.
    """
    from roomlight.errors import RoomlightError
    from roomlight.evaluation.crops.bench import run_crop_benchmark
    from roomlight.evaluation.harness.runner import parse_shard
    from roomlight.fitting.methods import method as method_record

    try:
        method_list = check_methods(_csv(methods) or methods_for(CROPS), methods_for(CROPS))
    except RoomlightError as exc:
        raise click.UsageError(str(exc)) from None
    prior = None
    if any(method_record(m).model == "prior" for m in method_list):
        prior, _ = load_prior(model, "run-crops", device="cpu")
    summary = run_crop_benchmark(crops, out_dir, method_list, prior, spp, parse_shard(shard) if shard else (0, 1),
                                 progress=not quiet)
    echo_run_summary("run-crops", summary, out_dir)


@click.command("report-crops")
@click.argument("results", type=click.Path(exists=True, file_okay=False))
@click.option("--reference", default="estimate", show_default=True, help="The method paired against the others.")
def report_crops(results, reference):
    """Tabulate a run-crops folder (report.md there): means per method and sphere, paired differences, and
    the field's published numbers on their own test sets."""
    from roomlight.evaluation.crops.bench import crop_report

    md = crop_report(results, reference)
    (Path(results) / "report.md").write_text(md)
    click.echo(md)
