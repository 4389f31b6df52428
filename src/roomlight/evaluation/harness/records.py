"""The files of a results folder, the same for every benchmark kind.

Layout of ``RES``::

    RES/run.json                              the run's settings (checked when a run resumes)
    RES/cases/<item>/<method>/result.json     one case's record (written last: marks the case done)
    RES/cases/<item>/<method>/error.json      instead, when the case failed (retried on the next run)

``<item>`` is what a method is run on: a synthetic scene (``<panorama>/<material>``) or a photo.
Every write goes through a temporary file and a rename, so a reader (or a resumed run) never sees
half a file.
"""

from __future__ import annotations

import json
import os
import traceback
from pathlib import Path


from roomlight.core.io.jsonable import json_default
from roomlight.evaluation.harness.errors import BenchError

__all__ = ["RESULT", "RUN_FILE", "json_default", "write_json", "record_failure", "check_settings", "check_run_file",
           "read_case_records", "collect_failures"]

RESULT = "result.json"
RUN_FILE = "run.json"
#: A case's own fit writes a result.json of its own in this sub-folder: not a case record.
_FIT_DIR = "fit"


def write_json(path: Path, data) -> None:
    """Write ``data`` as indented JSON through a temporary file, so a reader never sees half of it."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    tmp.write_text(json.dumps(data, indent=2, default=json_default))
    os.replace(tmp, path)


def record_failure(case_dir: Path, name: str, exc: BaseException) -> str:
    """Write the failed case ``name``'s ``error.json`` (message, type, traceback) into ``case_dir``
    and return the one-line summary a run prints; call it inside the ``except`` block.

    A later run retries the case: only ``result.json`` marks a case as done."""
    case_dir = Path(case_dir)
    case_dir.mkdir(parents=True, exist_ok=True)
    write_json(case_dir / "error.json", {"case": name, "error": str(exc), "type": type(exc).__name__,
                                         "traceback": traceback.format_exc()})
    return f"{type(exc).__name__}: {exc}"


def _differences(old, new, prefix: str = "") -> list[str]:
    """``name: old -> new`` for every differing value, nested settings named by their path."""
    if isinstance(old, dict) and isinstance(new, dict):
        return [d for k in sorted(set(old) | set(new), key=str)
                for d in _differences(old.get(k), new.get(k), f"{prefix}{k}.")]
    return [] if old == new else [f"{prefix.rstrip('.')}: {old!r} -> {new!r}"]


def check_settings(path, settings: dict, keys=None) -> None:
    """Refuse an output folder whose settings file ``path`` was written with other values of ``keys``
    (the settings that change what its items compute; every key when None), naming each difference;
    then record ``settings`` there. Every resumable command (benchmarks, experiments) goes through here."""
    f = Path(path)
    if f.is_file():
        try:
            old = json.loads(f.read_text())
        except ValueError:
            old = None
        if isinstance(old, dict):
            names = sorted(set(old) | set(settings)) if keys is None else [k for k in keys if k in old]
            diffs = [d for k in names for d in _differences(old.get(k), settings.get(k), f"{k}.")]
            if diffs:
                raise BenchError(f"{f.parent}: holds results made with other settings ({'; '.join(diffs)}); "
                                 "use the same settings, another --out, or delete it to start over")
    write_json(f, settings)


def check_run_file(out: Path, settings: dict, keys) -> None:
    """:func:`check_settings` of a results folder's ``run.json``."""
    check_settings(Path(out) / RUN_FILE, settings, keys)


def read_case_records(res_dir, required: tuple[str, ...], command: str) -> list[dict]:
    """Every case record (``result.json``) under ``RES/cases`` that has the ``required`` keys, sorted by
    path (item, then method); each gets ``_dir``, its folder. ``command`` names what writes them, for the
    error when there are none."""
    root = Path(res_dir) / "cases"
    if not root.is_dir():
        raise BenchError(f"{res_dir}: no results (expected {root}; run `{command}` first)")
    out = []
    for f in sorted(root.rglob(RESULT)):
        if _FIT_DIR in f.relative_to(root).parts[:-1]:
            continue
        try:
            rec = json.loads(f.read_text())
        except ValueError as exc:
            raise BenchError(f"{f}: not valid JSON: {exc}") from None
        if all(k in rec for k in required):
            rec["_dir"] = str(f.parent)
            out.append(rec)
    return out


def collect_failures(res_dir) -> list[dict]:
    """Every ``error.json`` of a case without a result."""
    root = Path(res_dir) / "cases"
    out = []
    for f in sorted(root.rglob("error.json")) if root.is_dir() else []:
        if not (f.parent / RESULT).is_file():
            try:
                out.append(json.loads(f.read_text()))
            except ValueError:
                out.append({"case": str(f.parent), "error": "unreadable error.json"})
    return out
