"""``roomlight bench``: the synthetic benchmark (build it, run the methods on it, report)."""

from __future__ import annotations

import click

from roomlight.evaluation.bench.builder import BenchConfig
from roomlight.evaluation.bench.runner import DEFAULT_EVAL_SPP
from roomlight.cli.common import RESOLUTION, RoomlightGroup, default_of, echo_run_summary, load_prior, parse_sets
from roomlight.fitting.inverse.config import FIT_PRESETS

#: ``--paper`` settings of ``bench make`` (supplementary "Synthetic scene design").
PAPER_MAKE = {"emitter_height": 512, "width": 1000, "height": 1000, "spp": 4096}
#: ``--paper`` setting of ``bench run`` (ground-truth comparisons at 4096 spp).
PAPER_EVAL_SPP = 4096


def _csv(value):
    if value is None:
        return None
    items = tuple(s.strip() for s in str(value).split(",") if s.strip())
    return items or None


@click.group("bench", cls=RoomlightGroup)
def command():
    """The synthetic benchmark of the paper (§4.2): make scenes, fit them, report Table 2.

    \b
      roomlight bench make --panos PANOS/ --out bench/        scenes from panoramas with depth
      roomlight bench run bench/ --out res/ --model RUN       fit and score every method
      roomlight bench report res/                             tables, figures, index.html

    The photo benchmark (rendered photographs of procedural rooms, true light transport):

    \b
      roomlight bench make-photos --out photos/ --n 8         photo cases + ground-truth probes
      roomlight bench run-photos photos/ --out pres/          fit-photo every method, score probes
      roomlight bench report-photos pres/                     tables, paired statistics, figures
    """


@command.command("make")
@click.option("--panos", required=True, type=click.Path(),
              help="Folder of panorama EXRs (R, G, B + Z depth), or one EXR.")
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False), help="Benchmark folder to write.")
@click.option("--n", type=int, default=25, show_default=True, help="Use the first N panoramas (sorted by name).")
@click.option("--seed", type=int, default=0, show_default=True, help="Base seed of the placements.")
@click.option("--paper", is_flag=True, help="The paper's settings: emitter 512x1024, images 1000x1000, 4096 spp.")
@click.option("--emitter-res", "emitter_height", type=int, default=None,
              help=f"Emitter height H (width 2H) the panoramas are resampled to {default_of(BenchConfig, 'emitter_height')}.")
@click.option("--res", type=RESOLUTION, default=None,
              help=f"Image size HxW [default: {BenchConfig.height}x{BenchConfig.width}].")
@click.option("--spp", type=int, default=None, help=f"Samples per pixel of the ground-truth renders {default_of(BenchConfig, 'spp')}.")
@click.option("--fov", type=float, default=None, help=f"Horizontal field of view in degrees {default_of(BenchConfig, 'fov')}.")
@click.option("--materials", default=None, help=f"Comma-separated materials [default: {','.join(BenchConfig.materials)}].")
@click.option("--shapes", default=None,
              help="Comma-separated input-view shapes: built-in names or .ply/.obj files; more than two: "
                   f"two are drawn per panorama [default: {','.join(BenchConfig.shapes)}].")
@click.option("--key", type=float, default=None, help=f"Exposure key: objects' log-average luminance {default_of(BenchConfig, 'key')}.")
@click.option("--one-material-each", "material_per_panorama", is_flag=True, default=None,
              help="One scene per panorama, the materials in turn (panorama k, sorted by name, gets material k mod "
                   "their number), instead of one per panorama and material.")
@click.option("--overwrite", is_flag=True, help="Rebuild panoramas that are already built.")
@click.option("--quiet", is_flag=True, help="No progress bar.")
def make(panos, out_dir, n, seed, paper, emitter_height, res, spp, fov, materials, shapes, key, material_per_panorama,
         overwrite, quiet):
    """Build benchmark scenes from the panoramas in --panos (one per panorama and material).

    Writes OUT/<panorama>/<material>/scene.json with the ground-truth emitter, linear EXR and
    8-bit renders of the input and evaluation views, and masks; and OUT/manifest.json. An
    interrupted build resumes where it stopped.
    """
    from roomlight.evaluation.bench.builder import make_benchmark

    cfg = BenchConfig(n=n, seed=seed)
    if paper:
        cfg = cfg.override(**PAPER_MAKE)
    height, width = res if res else (None, None)
    cfg = cfg.override(emitter_height=emitter_height, width=width, height=height, spp=spp, fov=fov,
                       materials=_csv(materials), shapes=_csv(shapes), key=key,
                       material_per_panorama=material_per_panorama or None)
    manifest = make_benchmark(panos, out_dir, cfg, overwrite=overwrite, progress=not quiet)
    if cfg.material_per_panorama:
        click.echo(f"{len(manifest['panoramas'])} panoramas, one material each ({', '.join(cfg.materials)} in turn) = "
                   f"{len(manifest['scenes'])} scenes -> {out_dir}")
    else:
        click.echo(f"{len(manifest['panoramas'])} panoramas x {len(cfg.materials)} materials = "
                   f"{len(manifest['scenes'])} scenes -> {out_dir}")


@command.command("run")
@click.argument("bench", type=click.Path())
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False), help="Results folder.")
@click.option("--methods", default=None,
              help="Comma-separated methods [default: all]; 'oracle' re-renders the true emitter (noise floor).")
@click.option("--model", type=click.Path(), default=None,
              help="Trained prior (run folder or checkpoint) for the prior methods [default: the prior bundled "
                   "with roomlight].")
@click.option("--preset", type=click.Choice(list(FIT_PRESETS)), default="paper", show_default=True,
              help="Fit preset: paper (the paper's settings) or fast (CPU-friendly); see `roomlight fit --help`.")
@click.option("--iterations", type=int, default=None, help="Override: optimisation steps.")
@click.option("--fit-spp", type=int, default=None, help="Override: samples per pixel per fitting step.")
@click.option("--set", "sets", multiple=True, metavar="FIELD=VALUE",
              help="Override any fit setting, e.g. --set lr=0.05 (repeatable).")
@click.option("--eval-spp", type=int, default=None, help=f"Samples per pixel of the scoring re-renders [default: {DEFAULT_EVAL_SPP}].")
@click.option("--paper", is_flag=True, help="Score at the paper's 4096 spp.")
@click.option("--shard", default=None, metavar="I/N", help="Run only cases I, I+N, I+2N, ... (0 <= I < N).")
@click.option("--scheduler", default=None, metavar="ADDRESS",
              help="Run the cases on the workers of this Dask scheduler (tcp://host:8786); needs roomlight[dask].")
@click.option("--quiet", is_flag=True, help="No progress bars.")
def run(bench, out_dir, methods, model, preset, iterations, fit_spp, sets, eval_spp, paper, shard, scheduler, quiet):
    """Fit every scene of BENCH with each method, re-render both views and score them.

    Each case writes OUT/cases/<panorama>/<material>/<method>/result.json; finished cases are
    skipped, so re-running resumes. Failed cases are reported and retried on the next run.
    """
    from roomlight.evaluation.bench.runner import parse_shard, run_benchmark
    from roomlight.fitting.inverse import fit_config

    cfg = fit_config(preset, iterations=iterations, spp=fit_spp, **parse_sets(sets))
    method_list = _csv(methods)
    from roomlight.evaluation.bench.runner import default_methods
    from roomlight.fitting.methods import needs_prior
    from roomlight.fitting.methods import method as method_record

    # the VENI methods load their own models (--set veni_model=..., veni_d_model=...)
    with_prior = [m for m in (method_list or default_methods())
                  if needs_prior(m) and method_record(m).takes_model_option(False)]
    prior = model_name = None
    if with_prior:
        prior, model_name = load_prior(model, f"--methods {','.join(with_prior)}")
    spp = eval_spp if eval_spp is not None else (PAPER_EVAL_SPP if paper else DEFAULT_EVAL_SPP)
    summary = run_benchmark(bench, out_dir, method_list, cfg, prior, eval_spp=spp, shard=parse_shard(shard),
                            progress=not quiet, scheduler=scheduler, model_name=model_name)
    echo_run_summary("bench run", summary, out_dir)


@command.command("report")
@click.argument("results", type=click.Path())
@click.option("--out", "out_dir", default=None, type=click.Path(file_okay=False),
              help="Report folder [default: RESULTS/report].")
@click.option("--no-figures", is_flag=True, help="Tables only (no per-scene figures).")
@click.option("--reference", default=None, metavar="METHOD",
              help="The method the paired tables compare with every other, scene by scene, e.g. veni-d "
                   "[default: prior].")
@click.option("--quiet", is_flag=True, help="No progress bar.")
def report(results, out_dir, no_figures, reference, quiet):
    """Table 2 (method x material x metric, mean ± std) of RESULTS as Markdown, CSV and JSON,
    paired per-scene differences of --reference against every other method with bootstrap
    intervals, a figure per scene, and index.html."""
    from roomlight.evaluation.bench.report import write_report

    paths = write_report(results, out_dir, figures=not no_figures, progress=not quiet, reference=reference)
    click.echo(paths["markdown"].read_text())
    click.echo(f"report -> {paths['html']}")


# The photo benchmark's commands (rendered photographs with full light transport as ground truth).
from roomlight.cli.photobench import make_photos, report_photos, run_photos  # noqa: E402

for _photo_command in (make_photos, run_photos, report_photos):
    command.add_command(_photo_command)

# The crop benchmark's commands (the field's three-sphere protocol).
from roomlight.cli.crops import make_crops, report_crops, run_crops  # noqa: E402

for _crop_command in (make_crops, run_crops, report_crops):
    command.add_command(_crop_command)
