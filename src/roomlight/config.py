"""The base of roomlight's settings dataclasses: strict ``to_dict`` / ``from_dict`` / ``override``.

A settings object is a frozen dataclass whose fields are plain values (numbers, strings, bools,
tuples, None). Saved as JSON it becomes a dict (tuples as lists); read back, an unknown name is an
error rather than a silently ignored typo, and lists become tuples again where the field's
default is a tuple. ``override`` is ``dataclasses.replace`` with the same check on names, so
``--set FIELD=VALUE`` on the command line and ``config.override(field=value)`` in code refuse
the same mistakes.
"""

from __future__ import annotations

from dataclasses import MISSING, asdict, fields, replace
from typing import Any, TypeVar

from roomlight.errors import RoomlightError

__all__ = ["StrictConfig", "check_field_names"]

C = TypeVar("C", bound="StrictConfig")


def check_field_names(cls, names, what: str) -> None:
    """Raise :class:`RoomlightError` naming every entry of ``names`` that is not a field of ``cls``."""
    known = {f.name for f in fields(cls)}
    bad = sorted(set(names) - known)
    if bad:
        raise RoomlightError(f"{what}: unknown field(s) {', '.join(bad)}; known: {', '.join(sorted(known))}")


class StrictConfig:
    """Mixin for frozen settings dataclasses (see the module docstring)."""

    def to_dict(self) -> dict[str, Any]:
        """Every field by name; tuples become lists (JSON's arrays)."""
        return {k: list(v) if isinstance(v, tuple) else v for k, v in asdict(self).items()}

    @classmethod
    def from_dict(cls: type[C], d: dict) -> C:
        """Inverse of :meth:`to_dict`; unknown names are refused, missing ones take their defaults."""
        check_field_names(cls, d, cls.__name__)
        return cls(**_tuples_back(cls, d))

    def override(self: C, **changes) -> C:
        """A copy with some fields changed; unknown names are refused."""
        check_field_names(type(self), changes, type(self).__name__)
        return replace(self, **_tuples_back(type(self), changes))


def _tuples_back(cls, d: dict) -> dict:
    """Lists for fields whose default is a tuple -> tuples (a JSON round trip gives lists)."""
    tuple_fields = {f.name for f in fields(cls) if f.default is not MISSING and isinstance(f.default, tuple)}
    return {k: tuple(v) if k in tuple_fields and isinstance(v, list) else v for k, v in d.items()}
