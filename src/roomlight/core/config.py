"""The base of roomlight's settings dataclasses: strict ``to_dict`` / ``from_dict`` / ``override``.

A settings object is a frozen dataclass whose fields are plain values (numbers, strings, bools,
tuples, None). Saved as JSON it becomes a dict (tuples as lists); read back, an unknown name is an
error rather than a silently ignored typo (the message names the closest valid field), a value of
the wrong type is an error naming the field and the type it needs, and lists become tuples again
where the field is a tuple. ``override`` is ``dataclasses.replace`` with the same checks, so
``--set FIELD=VALUE`` on the command line and ``config.override(field=value)`` in code refuse the
same mistakes.

:func:`check_keys` and :func:`check_type` are the same checks for files that are not a single
dataclass (scene descriptions, checkpoint ``config.json``, benchmark manifests).
"""

from __future__ import annotations

import difflib
import types
import typing
from dataclasses import MISSING, asdict, fields, replace
from pathlib import Path
from typing import Any, TypeVar, Union

from roomlight.errors import RoomlightError

__all__ = ["StrictConfig", "check_field_names", "check_keys", "check_type", "closest_name", "ConfigError"]

C = TypeVar("C", bound="StrictConfig")


class ConfigError(RoomlightError):
    """A settings mapping has an unknown field or a value of the wrong type; the message gives its path."""


def closest_name(name: str, known) -> str | None:
    """The entry of ``known`` most like ``name`` (difflib), or None when nothing is close."""
    match = difflib.get_close_matches(str(name), [str(k) for k in known], n=1, cutoff=0.6)
    return match[0] if match else None


def _unknown_message(key, known, where: str) -> str:
    guess = closest_name(key, known)
    hint = f"did you mean {guess!r}? " if guess else ""
    return f"{where}.{key}: unknown field ({hint}known: {', '.join(sorted(map(str, known)))})"


def check_keys(mapping, known, where: str, error=ConfigError) -> None:
    """Raise ``error`` for the first key of ``mapping`` not in ``known``, naming its path and the closest name."""
    if not isinstance(mapping, dict):
        raise error(f"{where}: expected a mapping, got {_describe(mapping)}")
    known = set(known)
    for key in mapping:
        if key not in known:
            raise error(_unknown_message(key, known, where))


def check_field_names(cls, names, what: str) -> None:
    """Raise :class:`ConfigError` naming the first entry of ``names`` that is not a field of ``cls``."""
    check_keys({n: None for n in names}, {f.name for f in fields(cls)}, what)


def _describe(value) -> str:
    text = repr(value)
    if len(text) > 40:
        text = text[:37] + "..."
    return f"{type(value).__name__} {text}"


def _type_name(hint) -> str:
    origin = typing.get_origin(hint)
    if origin in (Union, types.UnionType):
        return " or ".join(_type_name(a) for a in typing.get_args(hint))
    if origin is tuple:
        args = typing.get_args(hint)
        if len(args) == 2 and args[1] is Ellipsis:
            return f"a list of {_type_name(args[0])}"
        return f"a list of {len(args)} ({', '.join(_type_name(a) for a in args)})"
    if origin is typing.Literal:
        return "one of " + ", ".join(repr(a) for a in typing.get_args(hint))
    if hint is type(None):
        return "null"
    if hint is Path:
        return "a path (str)"
    return getattr(hint, "__name__", str(hint))


def check_type(value, hint, where: str, error=ConfigError):
    """``value`` checked against the type annotation ``hint``; lists become tuples where a tuple is wanted.

    Supports bool, int, float (an int is accepted), str, Path (a str is accepted), dict, None,
    unions, ``Literal``, ``tuple[X, ...]`` and ``tuple[X, Y]``; other annotations are not checked.
    """
    origin = typing.get_origin(hint)
    if origin in (Union, types.UnionType):
        for arg in typing.get_args(hint):
            try:
                return check_type(value, arg, where, error)
            except error:
                continue
        raise error(f"{where}: expected {_type_name(hint)}, got {_describe(value)}")
    if origin is typing.Literal:
        if value in typing.get_args(hint):
            return value
        raise error(f"{where}: expected {_type_name(hint)}, got {_describe(value)}")
    if origin is tuple:
        args = typing.get_args(hint)
        if not isinstance(value, (list, tuple)):
            raise error(f"{where}: expected {_type_name(hint)}, got {_describe(value)}")
        if len(args) == 2 and args[1] is Ellipsis:
            return tuple(check_type(v, args[0], f"{where}[{i}]", error) for i, v in enumerate(value))
        if len(value) != len(args):
            raise error(f"{where}: expected {_type_name(hint)}, got {len(value)} entries")
        return tuple(check_type(v, a, f"{where}[{i}]", error) for i, (v, a) in enumerate(zip(value, args)))
    if origin is dict or hint is dict:
        if isinstance(value, dict):
            return value
    elif hint is type(None):
        if value is None:
            return value
    elif hint is bool:
        if isinstance(value, bool):
            return value
    elif hint is int:
        if isinstance(value, int) and not isinstance(value, bool):
            return value
    elif hint is float:
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            return value
    elif hint is str:
        if isinstance(value, str):
            return value
    elif hint is Path:
        if isinstance(value, (str, Path)):
            return Path(value)
    else:
        return value  # an annotation this checker does not know: left to the class
    raise error(f"{where}: expected {_type_name(hint)}, got {_describe(value)}")


def _hints(cls) -> dict:
    try:
        return typing.get_type_hints(cls)
    except Exception:  # an annotation that cannot be resolved: names are still checked
        return {}


def checked_fields(cls, d: dict, where: str | None = None) -> dict:
    """``d`` with its names checked against the fields of dataclass ``cls`` and its values against their types."""
    where = where or cls.__name__
    check_keys(d, {f.name for f in fields(cls)}, where)
    hints = _hints(cls)
    return {k: check_type(v, hints[k], f"{where}.{k}") if k in hints else v for k, v in d.items()}


class StrictConfig:
    """Mixin for frozen settings dataclasses (see the module docstring)."""

    def to_dict(self) -> dict[str, Any]:
        """Every field by name; tuples become lists (JSON's arrays)."""
        return {k: _lists(v) for k, v in asdict(self).items()}

    @classmethod
    def from_dict(cls: type[C], d: dict, where: str | None = None) -> C:
        """Inverse of :meth:`to_dict`; unknown names and wrong types are refused, missing ones take their defaults.

        ``where`` prefixes the field's path in messages (default: the class name).
        """
        return cls(**_tuples_back(cls, checked_fields(cls, d, where)))

    def override(self: C, **changes) -> C:
        """A copy with some fields changed; unknown names and wrong types are refused."""
        return replace(self, **_tuples_back(type(self), checked_fields(type(self), changes)))


def _lists(value):
    if isinstance(value, tuple):
        return [_lists(v) for v in value]
    if isinstance(value, Path):
        return str(value)
    return value


def _tuples_back(cls, d: dict) -> dict:
    """Lists for fields whose default is a tuple -> tuples (a JSON round trip gives lists)."""
    tuple_fields = {f.name for f in fields(cls) if f.default is not MISSING and isinstance(f.default, tuple)}
    return {k: tuple(v) if k in tuple_fields and isinstance(v, list) else v for k, v in d.items()}
