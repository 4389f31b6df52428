"""``roomlight bench make-photos | run-photos | report-photos``: the photo benchmark (attached to ``bench``)."""

from __future__ import annotations

from pathlib import Path

import click

from roomlight.cli.common import (FINITE, RESOLUTION, default_of, echo_run_summary, load_prior, parse_sets,
                                 set_view_encoder, sets_option)
from roomlight.evaluation.photobench.config import SUITES, PhotoBenchConfig, suite_config
from roomlight.evaluation.photobench.runner import DEFAULT_EVAL_SPP, DEFAULT_METHODS, KNOWN_METHODS

__all__ = ["make_photos", "run_photos", "report_photos"]


def _csv(value):
    if value is None:
        return None
    items = tuple(s.strip() for s in str(value).split(",") if s.strip())
    return items or None


def _shard(text):
    from roomlight.evaluation.harness.runner import parse_shard

    return parse_shard(text)


@click.command("make-photos")
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False), help="Benchmark folder to write.")
@click.option("--suite", type=click.Choice(SUITES), default="rooms", show_default=True,
              help="rooms: the room generator's own rooms, cameras and object colours; wide: photos that differ "
                   "from them on purpose (rare rooms, repainted walls, lamps of several colour temperatures, "
                   "table-top to standing cameras, 40-90 degree lenses, black to white and metal objects, and "
                   "every third photo lit by a real captured HDR panorama; docs/benchmark.md).")
@click.option("--captured-lights", type=click.Path(file_okay=False), default=None, metavar="DIR",
              help="HDR panoramas (*.exr) for the wide suite's captured-light photos [default: Blender's CC0 "
                   "studio lights, installed by `make blender`].")
@click.option("--n", type=int, default=PhotoBenchConfig.n, show_default=True, help="Photos (indices 0 .. N-1).")
@click.option("--seed", type=int, default=0, show_default=True, help="Base seed (rooms, staging, materials, renders).")
@click.option("--res", type=RESOLUTION, default=None,
              help=f"Photo size HxW [default: {PhotoBenchConfig.height}x{PhotoBenchConfig.width}].")
@click.option("--spp", type=int, default=None,
              help=f"Samples per pixel of the photo {default_of(PhotoBenchConfig, 'spp')}.")
@click.option("--probe-spp", type=int, default=None,
              help="Samples per pixel of the ground-truth probe renders (only the window around the probes) "
                   f"{default_of(PhotoBenchConfig, 'probe_spp')}.")
@click.option("--insert-spp", type=int, default=None,
              help="Samples per pixel of the inserted objects' clean truth, the image their composites are "
                   "scored against (rendered with a seed of its own; 0: none, scored against the render with "
                   f"the photo's own samples) {default_of(PhotoBenchConfig, 'insert_spp')}.")
@click.option("--fov", type=FINITE, default=None,
              help=f"Horizontal field of view in degrees {default_of(PhotoBenchConfig, 'fov')}.")
@click.option("--probes", type=int, default=None,
              help=f"Probe positions per photo {default_of(PhotoBenchConfig, 'probes')}.")
@click.option("--inserts", type=int, default=None,
              help="New objects rendered into the room as the insertion truth "
                   f"{default_of(PhotoBenchConfig, 'inserts')}.")
@click.option("--inserts-at", "inserts_at", type=click.Choice(["probes", "stratified"]), default=None,
              help="Where the new objects go: at the first probe positions, where the reference light is "
                   "captured around (probes), or one per stratum of the visible surfaces: near, middle and far "
                   "by distance, and raised (a table, a shelf) (stratified; up to 4) [default: probes].")
@click.option("--depth-noise", type=FINITE, default=None, metavar="SIGMA",
              help="Degrade the depth the methods get: depth x exp(SIGMA n), n a smooth unit-RMS random field "
                   "(the truth keeps the exact depth) [default: 0].")
@click.option("--depth-scale", type=FINITE, default=None, metavar="F",
              help="Scale the depth the methods get by F (a wrong metric scale) [default: 1].")
@click.option("--shard", default=None, metavar="I/N", help="Build only photos I, I+N, I+2N, ... (0 <= I < N).")
@click.option("--set", "sets", multiple=True, metavar="FIELD=VALUE",
              help="Change any photo benchmark setting (PhotoBenchConfig; docs/benchmark.md), e.g. "
                   "--set oracle_height=32 --set objects=[2,2] (repeatable).")
@click.option("--overwrite", is_flag=True, help="Rebuild photos that are already built.")
@click.option("--quiet", is_flag=True, help="No progress bar.")
def make_photos(out_dir, suite, captured_lights, n, seed, res, spp, probe_spp, insert_spp, fov, probes, inserts,
                inserts_at, depth_noise, depth_scale, shard, sets, overwrite, quiet):
    """Render the photo benchmark: photos of procedural rooms with inserted objects, and their truth.

    Each OUT/photo-NNNNN/ is a photo case (image.exr, depth.exr, mask.png, camera.json; what
    `roomlight fit-photo` reads) plus truth/: probe spheres (diffuse, matte, mirror) path-traced
    at several positions near the objects, their masks and positions, the objects' true materials,
    the exact depth and an oracle light. Finished photos are skipped; photos built with other
    --depth-noise/--depth-scale only get a new depth.exr, and those built with another --insert-spp
    (or before the clean insertion truth existed) only a new truth/insert_clean.exr.
    OUT/manifest.json lists the photos.
    """
    from roomlight.evaluation.photobench.builder import make_photo_benchmark

    cfg = suite_config(suite, n=n, seed=seed)
    height, width = res if res else (None, None)
    cfg = cfg.override(width=width, height=height, spp=spp, probe_spp=probe_spp, insert_spp=insert_spp, fov=fov,
                       probes=probes, inserts=inserts,
                       insert_placement=inserts_at, depth_noise=depth_noise, depth_scale=depth_scale, **parse_sets(sets))
    result = make_photo_benchmark(out_dir, cfg, overwrite=overwrite, shard=_shard(shard), progress=not quiet,
                                  captured_lights=captured_lights)
    click.echo(f"make-photos: {len(result['built'])} built, {len(result['updated'])} with a new depth, "
               f"{len(result['insert_updated'])} with a new clean insertion truth, "
               f"{len(result['skipped'])} already built, {len(result['failed'])} failed; "
               f"{len(result['photos'])} photos in {out_dir}/manifest.json")
    for name, err in result["failed"].items():
        click.echo(f"  failed {name}: {err}", err=True)
    if result["failed"]:
        raise SystemExit(1)


@click.command("run-photos")
@click.argument("bench", type=click.Path())
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False), help="Results folder.")
@click.option("--methods", default=None,
              help=f"Comma-separated methods [default: {','.join(DEFAULT_METHODS)}]; also oracle and oracle-envmap "
                   "(the photo's room captured at the probes, as a 2.5D light or at infinity: references), "
                   "prior-ceiling (the prior's latent fitted to that room: the prior's own ceiling), "
                   "prior-view, prior-samples, prior-zero (the prior's fit from a fixed start, as fit-photo --init), "
                   "naive-paste (a uniform light of the photo's mean colour, its inserted objects pasted alone), "
                   "and estimate, estimate-refine, estimate-depth-optional (roomlight estimate on the photo alone: "
                   "no depth, no mask).")
@click.option("--model", type=click.Path(), default=None,
              help="Trained prior for the prior methods [default: the prior bundled with roomlight].")
@click.option("--view-encoder", "view_encoder", type=click.Path(exists=True, file_okay=False), default=None,
              help="The prior methods read each photo with this view encoder (a folder written by "
                   "train-view-encoder, e.g. RUN/best) instead of the one beside the prior.")
@click.option("--preset", default="paper", show_default=True,
              help="The fit-photo preset (paper, balanced, fast; see `roomlight fit-photo --help`).")
@click.option("--eval-spp", type=int, default=DEFAULT_EVAL_SPP, show_default=True,
              help="Samples per pixel of the probe renders under the recovered lights.")
@click.option("--shard", default=None, metavar="I/N", help="Run only cases I, I+N, I+2N, ... (0 <= I < N).")
@click.option("--scheduler", default=None, metavar="ADDRESS",
              help="Run the cases on the workers of this Dask scheduler (tcp://host:8786); needs roomlight[dask].")
@sets_option("fit-photo setting")
@click.option("--quiet", is_flag=True, help="No progress bar.")
def run_photos(bench, out_dir, methods, model, view_encoder, preset, eval_spp, shard, scheduler, sets, quiet):
    """Fit every photo of BENCH with each method and score the probes under the recovered light.

    Photos built with inserted objects (make-photos --inserts, default 2) also get them composited under
    each light by roomlight insert's differential rendering, scored against their path-traced truth.

    Each case writes OUT/cases/<photo>/<method>/result.json (probe scores per material and probe,
    material errors); finished cases are skipped, so re-running resumes. Failed cases are
    reported and retried on the next run.
    """
    from roomlight.evaluation.photobench.runner import run_photo_benchmark

    from roomlight.errors import RoomlightError
    from roomlight.fitting.methods import check_methods
    from roomlight.fitting.methods import method as method_record

    try:
        method_list = check_methods(_csv(methods) or DEFAULT_METHODS, KNOWN_METHODS)
    except RoomlightError as exc:
        raise click.UsageError(str(exc)) from None
    with_prior = [m for m in method_list if method_record(m).model == "prior"]  # VENI loads its own models
    prior = model_name = None
    if with_prior:
        prior, model_name = load_prior(model, f"--methods {','.join(with_prior)}")
        if view_encoder is not None:
            set_view_encoder(prior, view_encoder)
    elif view_encoder is not None:
        raise click.UsageError(f"--view-encoder is read by the prior's methods only, not by {methods}")
    summary = run_photo_benchmark(bench, out_dir, method_list, preset, prior, eval_spp, _shard(shard),
                                  progress=not quiet, overrides=parse_sets(sets), model_name=model_name,
                                  scheduler=scheduler,
                                  view_encoder_name=None if view_encoder is None else str(Path(view_encoder).resolve()))
    echo_run_summary("run-photos", summary, out_dir)


@click.command("report-photos")
@click.argument("results", type=click.Path())
@click.option("--out", "out_dir", default=None, type=click.Path(file_okay=False),
              help="Report folder [default: RESULTS/report].")
@click.option("--no-figures", is_flag=True, help="Tables only (no per-photo figures).")
@click.option("--reference", default=None, metavar="METHOD",
              help="The method the paired tables compare with every other, photo by photo, e.g. veni-d "
                   "[default: prior].")
@click.option("--quiet", is_flag=True, help="No progress bar.")
def report_photos(results, out_dir, no_figures, reference, quiet):
    """The photo benchmark's tables (probes: method x material x metric; recovered materials), paired
    statistics, a figure per photo and index.html, from the RESULTS of run-photos."""
    from roomlight.evaluation.photobench.report import write_photo_report

    paths = write_photo_report(results, out_dir, figures=not no_figures, progress=not quiet, reference=reference)
    click.echo(paths["markdown"].read_text())
    click.echo(f"report -> {paths['html']}")
