"""Which representation shows a panorama's radiance: the three emitter kinds of the paper.

- ``mesh``:      the 2.5D area light (depth places the vertices);
- ``sphere:R``:  the same mesh at a constant radius R in scene units (a sphere proxy);
- ``envmap``:    the radiance at infinity.
"""

from __future__ import annotations

from dataclasses import dataclass

from roomlight.errors import RoomlightError

__all__ = ["EmitterKind", "parse_emitter_kind"]


@dataclass(frozen=True)
class EmitterKind:
    """Which representation shows the radiance: ``mesh``, ``envmap`` or ``sphere`` (with radius)."""

    name: str
    radius: float | None = None

    def __str__(self) -> str:
        return f"sphere:{self.radius:g}" if self.name == "sphere" else self.name


def parse_emitter_kind(text: str | EmitterKind) -> EmitterKind:
    """Parse ``mesh``, ``envmap`` or ``sphere:R`` (R in scene units)."""
    if isinstance(text, EmitterKind):
        return text
    name, _, arg = str(text).partition(":")
    if name in ("mesh", "envmap") and not arg:
        return EmitterKind(name)
    if name == "sphere":
        try:
            r = float(arg)
        except ValueError:
            r = float("nan")
        if r > 0:
            return EmitterKind("sphere", r)
        raise RoomlightError(f"emitter kind {text!r}: a sphere needs a positive radius, e.g. 'sphere:3.5'")
    raise RoomlightError(f"emitter kind {text!r}: expected 'mesh', 'envmap' or 'sphere:R'")
