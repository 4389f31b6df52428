"""``roomlight`` command-line entry point: one sub-command per file in this package."""

from __future__ import annotations

from roomlight.cli.threads import apply_thread_policy, default_threads, parse_thread_request, prepare_environment

prepare_environment()  # passive OpenMP waiting: before anything imports torch

import click  # noqa: E402

from roomlight import __version__  # noqa: E402
from roomlight.cli.common import RoomlightGroup  # noqa: E402


class ThreadCount(click.ParamType):
    """A positive whole number of threads, or ``auto`` (follow the machine's load)."""

    name = "threads"

    def convert(self, value, param, ctx):
        try:
            return parse_thread_request(value)
        except ValueError as e:
            self.fail(str(e), param, ctx)


@click.group(cls=RoomlightGroup, context_settings={"help_option_names": ["-h", "--help"], "max_content_width": 100})
@click.version_option(__version__, prog_name="roomlight")
@click.option("--threads", type=ThreadCount(), default=None, metavar="N|auto",
              help="Threads for torch and Mitsuba [default: $ROOMLIGHT_THREADS, else the CPUs available]. "
                   "'auto': the CPUs other processes leave free, measured again between long phases "
                   "(the numbers then depend on what runs beside them; docs/troubleshooting.md).")
@click.option("--deterministic", is_flag=True,
              help="Bit-identical results run to run: Mitsuba's CPU backend on one thread (slower; "
                   "docs/troubleshooting.md). Also $ROOMLIGHT_DETERMINISTIC=1.")
def cli(threads, deterministic):
    """roomlight: spatially-varying indoor illumination as 2.5D area lights.

    Panoramas of HDR radiance + radial depth become emissive meshes that light a scene
    with parallax and falloff, rendered and optimised through Mitsuba 3.

    \b
    Start with:
      roomlight info                       versions, Mitsuba variant, device
      roomlight demo                       the built-in end-to-end example
      roomlight emitter PANO --out DIR     panorama -> emitter (PLY, EXR, Mitsuba XML)
      roomlight render DIR --out DIR       render a view of an emitter scene
      roomlight synth --n N --out DIR       render a dataset of procedural rooms
      roomlight prepare IN --out DIR       real captures -> training data (nadir, depth)
      roomlight train --data DIR --out RUN     train the prior on panoramas
      roomlight train-view-encoder --data DIR --out RUN   the photo fit's start, for a prior
      roomlight sample --model RUN --out DIR   draw rooms from the prior
      roomlight fit SCENE --method M --out DIR   recover illumination from an image
      roomlight estimate PHOTO --out DIR    the light from any photograph, in seconds
      roomlight fit-photo IMAGE --out DIR   light + materials from one photograph
      roomlight insert FIT --object NAME --at X,Y --out c.png   objects into the fitted photograph
      roomlight bench make|run|report      the synthetic benchmark
      roomlight view PATH --out page.html  an interactive viewer of a 2.5D light
      roomlight export PATH --out light.glb   the light for Blender / three.js / USD
      roomlight experiment capacity|ablate|cost   the paper's supplementary analyses
    """
    apply_thread_policy(threads)
    if deterministic:
        import os

        os.environ["ROOMLIGHT_DETERMINISTIC"] = "1"


def _register():
    from roomlight.cli import (bench, convert, data, demo, emitter, estimate, eval_prior, experiment, export, fit,
                               fit_pano, fit_photo, info, insert, prepare, render, sample, synth, train, train_view_encoder,
                               view)

    for mod in (info, emitter, render, synth, prepare, data, train, train_view_encoder, fit_pano, eval_prior, sample, convert, fit,
                estimate, fit_photo, insert, bench, demo, view, export, experiment):
        cli.add_command(mod.command)


_register()


def main():  # console-script entry point
    default_threads()
    cli(prog_name="roomlight")


if __name__ == "__main__":
    main()
