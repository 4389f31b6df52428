"""Shared pieces of the command-line interface: argument types and error reporting."""

from __future__ import annotations

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
    """``WIDTHxHEIGHT`` for images or ``HxW`` for panoramas (the option's help says which)."""

    name = "AxB"

    def convert(self, value, param, ctx):
        if isinstance(value, tuple):
            return value
        try:
            a, b = str(value).lower().split("x")
            a, b = int(a), int(b)
            if a <= 0 or b <= 0:
                raise ValueError
            return a, b
        except ValueError:
            self.fail(f"expected two positive integers like 256x256, got {value!r}", param, ctx)


VEC3 = Vec3()
RESOLUTION = Resolution()


def fail(message: str) -> None:
    """Stop the command with a one-line error (exit code 2), no stack trace."""
    raise click.ClickException(message)


class RoomlightGroup(click.Group):
    """A click group that reports :class:`RoomlightError` as a clean one-line message."""

    def invoke(self, ctx):
        try:
            return super().invoke(ctx)
        except RoomlightError as exc:
            click.echo(f"error: {exc}", err=True)
            ctx.exit(2)
