"""Shared pieces of the command-line interface: argument types, ``--set``, defaults and error reporting."""

from __future__ import annotations

import json
from pathlib import Path

import click

from roomlight.errors import RoomlightError


class Vec3(click.ParamType):
    """Three comma-separated numbers, e.g. ``0,1.5,-2``."""

    name = "x,y,z"

    def convert(self, value, param, ctx):
        if isinstance(value, (tuple, list)):
            return tuple(float(v) for v in value)
        parts = str(value).replace(" ", "").split(",")
        try:
            if len(parts) != 3:
                raise ValueError
            return tuple(float(p) for p in parts)
        except ValueError:
            self.fail(f"expected three comma-separated numbers like 0,1.5,-2, got {value!r}", param, ctx)


class Resolution(click.ParamType):
    """``HxW``: height, then width, in pixels (``256x512``); a single number ``N`` means ``NxN``.

    Every ``--res`` of the command line means this, images and panoramas alike (a panorama's W is
    2H). Returns ``(height, width)``.
    """

    name = "HxW"

    def convert(self, value, param, ctx):
        if isinstance(value, tuple):
            return value
        text = str(value).lower().strip()
        try:
            h, w = text.split("x") if "x" in text else (text, text)
            h, w = int(h), int(w)
            if h <= 0 or w <= 0:
                raise ValueError
            return h, w
        except ValueError:
            self.fail(f"expected HEIGHTxWIDTH like 128x256 (or one number for a square), got {value!r}", param, ctx)


def parse_sets(items, option: str = "--set") -> dict:
    """``FIELD=VALUE`` strings of a repeatable ``--set`` option -> ``{field: value}``.

    Values are JSON when they parse (numbers, ``true``, ``[64, 128]``, ``null``), else YAML's
    plain scalars (``True``, ``[64,128]``), else the string itself. Dashes in a name become
    underscores; ``a.b=VALUE`` sets entry ``b`` of the nested mapping ``a`` (``--set loss.peak=0``).
    Every command with ``--set`` uses this, and the settings class then refuses unknown names.
    """
    out: dict = {}
    for item in items:
        key, sep, raw = str(item).partition("=")
        key = key.strip().replace("-", "_")
        if not sep or not key:
            fail(f"{option} {item!r}: expected FIELD=VALUE, e.g. {option} lr=0.05")
        out_key, _, sub = key.partition(".")
        value = _parse_value(raw)
        if sub:
            out.setdefault(out_key, {})[sub] = value
        else:
            out[key] = value
    return out


def _parse_value(raw: str):
    try:
        return json.loads(raw)
    except json.JSONDecodeError:
        pass
    import yaml

    try:
        value = yaml.safe_load(raw)
    except yaml.YAMLError:
        return raw
    return value if isinstance(value, (bool, int, float, list)) else raw


def default_of(cls, name: str) -> str:
    """``[default: VALUE]`` for a help string, read from the settings dataclass ``cls`` (the class
    attribute a dataclass field with a plain default leaves behind), so help never restates it."""
    value = getattr(cls, name)
    if isinstance(value, tuple) and len(value) == 2 and all(isinstance(v, int) for v in value):
        value = f"{value[0]}x{value[1]}"
    return f"[default: {value}]"


class FiniteFloat(click.ParamType):
    """A finite number: NaN and infinities are refused (``float`` would accept them)."""

    name = "VALUE"

    def convert(self, value, param, ctx):
        import math

        try:
            v = float(value)
        except (TypeError, ValueError):
            self.fail(f"expected a finite number, got {value!r}", param, ctx)
        if not math.isfinite(v):
            self.fail(f"expected a finite number (-inf < VALUE < inf), got {value!r}", param, ctx)
        return v


VEC3 = Vec3()
RESOLUTION = Resolution()
FINITE = FiniteFloat()
#: A panorama height (width 2x): at least 1 pixel, at most 8192.
HEIGHT = click.IntRange(1, 8192)


def repair_options(command):
    """``--clamp-negative`` and ``--fill-nonfinite VALUE``: the repairs a command reading panoramas offers.

    Without them a panorama with negative or NaN/inf radiance is refused; with them it is repaired
    and the number of changed pixels reported.
    """
    command = click.option("--fill-nonfinite", type=FINITE, default=None, metavar="VALUE",
                           help="Replace NaN/inf radiance by VALUE (reports how many changed).")(command)
    return click.option("--clamp-negative", is_flag=True,
                        help="Set negative radiance values to 0 (reports how many changed).")(command)


def sets_option(what: str):
    """The shared repeatable ``--set FIELD=VALUE`` option (read with :func:`parse_sets`)."""
    return click.option("--set", "sets", multiple=True, metavar="FIELD=VALUE",
                        help=f"Override any {what} field (repeatable), e.g. --set lr=0.05.")


class InputError(click.ClickException):
    """An input the command cannot use: ``error: MESSAGE`` on one line of stderr, exit code 2
    (the same as a :class:`RoomlightError` raised deeper down)."""

    exit_code = 2

    def show(self, file=None) -> None:
        click.echo(f"error: {self.format_message()}", err=True)


def parse_reference_albedo(text: str) -> tuple[int, float]:
    """``--reference-albedo LABEL=ALBEDO`` as (label, albedo); a one-line error for anything else (the
    albedo's range and the label's existence are checked where the photograph is known)."""
    label, _, value = str(text).partition("=")
    try:
        return int(label), float(value)
    except ValueError:
        raise RoomlightError(f"--reference-albedo {text!r}: write LABEL=ALBEDO, e.g. 2=0.8") from None


def fail(message: str) -> None:
    """Stop the command with a one-line error (exit code 2), no stack trace."""
    raise InputError(message)


def set_view_encoder(prior, path) -> None:
    """Read photographs with the view encoder in ``path`` (``--view-encoder``, a folder written by
    train-view-encoder) instead of the one beside ``prior``; one trained for other prior weights is
    refused, as its latents would mean nothing to this decoder."""
    from roomlight.prior.model.view_encoder import ViewEncoder

    encoder = ViewEncoder.from_pretrained(path, prior.config)
    if not encoder.trained_for(getattr(prior, "_weights_sha256", None)):
        fail(f"--view-encoder {path}: trained for other prior weights than the prior in use; "
             "pass that prior's --model, or train an encoder for this one with `roomlight train-view-encoder`")
    prior.set_view_encoder(encoder)


def load_prior(model, needed_by: str, device: str | None = None):
    """The prior of ``--model MODEL`` (a model folder, a training run or the authors' run), or the
    bundled one when MODEL is None, on the device Mitsuba renders on so that decoded maps reach the
    renderer without copies.

    ``needed_by`` names what asked for it (``"--method prior"``): in the note printed to stderr when
    the bundled prior is taken, and in the error when there is no prior at all.
    ``device`` overrides the renderer's device (a command that renders nothing need not load Mitsuba).
    Returns ``(model, path)``: the ``PanoVAE`` and the folder it was read from (for the records)."""
    if model is None:
        from roomlight.demo import bundled_prior_path

        model = bundled_prior_path()
        if model is None:
            fail(f"{needed_by} needs --model (a trained prior); this installation has no bundled prior")
        click.echo(f"note: {needed_by} without --model: using the bundled prior ({model}), a small CPU-trained one; "
                   "pass --model RUN for your own", err=True)
    from roomlight.prior.model.runs import load_run_model

    if device is None:
        from roomlight.core.render.variant import torch_device

        device = torch_device()
    return load_run_model(model, device=device), str(Path(model).resolve())


def echo_run_summary(command: str, summary, out_dir) -> None:
    """Print a benchmark run's outcome (``summary.done``, ``.skipped``, ``.failed``: name -> error)
    and exit with status 1 when a case failed, so scripts notice; the failed cases are retried on
    the next run."""
    rescored = getattr(summary, "rescored", [])
    click.echo(f"{command}: {len(summary.done)} done, {len(summary.skipped)} already done"
               + (f" ({len(rescored)} scored again against a new insertion truth)" if rescored else "")
               + f", {len(summary.failed)} failed -> {out_dir}")
    for name, err in summary.failed.items():
        click.echo(f"  failed {name}: {err}", err=True)
    if summary.failed:
        raise SystemExit(1)


def echo_fixes(fixes) -> None:
    """Report repairs applied to an input (``--clamp-negative``, ``--fill-nonfinite``), one note each."""
    for fix in fixes:
        click.echo(f"note: {fix}", err=True)


class RoomlightGroup(click.Group):
    """A click group that reports :class:`RoomlightError` as a clean one-line message."""

    def invoke(self, ctx):
        try:
            return super().invoke(ctx)
        except RoomlightError as exc:
            click.echo(f"error: {exc}", err=True)
            ctx.exit(2)
