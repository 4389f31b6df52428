"""One runner for every benchmark kind: cases listed, sharded, resumed, run here or on a Dask cluster,
failures recorded.

A benchmark kind supplies its items (scenes, photos), the methods, and one function that runs a case
and writes its ``result.json`` (:mod:`roomlight.evaluation.harness.records`); :func:`run_cases` does the rest the
same way for all of them:

- a case whose ``result.json`` exists is skipped (runs resume where they stopped);
- ``shard=(i, n)`` takes cases ``i, i + n, i + 2n, ...`` of the full list, so ``n`` processes (or
  machines sharing ``RES``) split the work without overlap;
- a failing case writes ``error.json`` and the run goes on; Ctrl-C stops it at once (the case in
  progress has written nothing final, so a rerun repeats it);
- between cases the thread count follows the machine's load (only a count roomlight chose);
- ``scheduler``: a Dask scheduler address or cluster runs the cases on its workers
  (:func:`roomlight.core.cluster.map_unordered`); the files are the same as in a serial run.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path

from roomlight.evaluation.harness.errors import BenchError
from roomlight.evaluation.harness.records import RESULT, record_failure

__all__ = ["Case", "RunSummary", "parse_shard", "shard_cases", "run_cases"]


@dataclass(frozen=True)
class Case:
    """One (item, method) pair of a benchmark.

    Attributes:
        item: the scene (``<panorama>/<material>``) or photo id; its cases live in ``RES/cases/<item>/``.
        method: the method's name (:mod:`roomlight.fitting.methods`).
        source: where the item is read from (a scene.json, a photo case folder).
    """

    item: str
    method: str
    source: Path

    @property
    def name(self) -> str:
        """``<item>/<method>``, as runs print it."""
        return f"{self.item}/{self.method}"

    def directory(self, out) -> Path:
        return Path(out) / "cases" / self.item / self.method


@dataclass
class RunSummary:
    """What one call of a benchmark run did: the names of the cases finished now, skipped as already
    finished, failed (name -> error), and, of the skipped ones, those whose scores were brought up to date
    (the photo benchmark's inserted objects scored again against a new truth)."""

    done: list[str] = field(default_factory=list)
    skipped: list[str] = field(default_factory=list)
    failed: dict[str, str] = field(default_factory=dict)
    rescored: list[str] = field(default_factory=list)


def parse_shard(text: str | tuple | None) -> tuple[int, int]:
    """``"i/n"`` (0 <= i < n) -> (i, n); None -> (0, 1)."""
    if text is None:
        return 0, 1
    if isinstance(text, tuple):
        i, n = text
    else:
        try:
            a, b = str(text).split("/")
            i, n = int(a), int(b)
        except ValueError:
            raise BenchError(f"--shard: expected i/n such as 0/4, got {text!r}") from None
    if not (n >= 1 and 0 <= i < n):
        raise BenchError(f"--shard: need 0 <= i < n, got {i}/{n}")
    return i, n


def shard_cases(cases: list, shard=(0, 1)) -> list:
    """Cases ``i, i + n, ...`` of the list, for ``shard = (i, n)``."""
    i, n = shard
    return list(cases)[i::n]


def _attempt(case: Case, out: Path, run_one: Callable) -> tuple[str, str | None]:
    """Run one case; a failure is written to its ``error.json`` and returned as text."""
    from roomlight.core.render.variant import recheck_threads

    recheck_threads()  # between cases the load may have changed (followed only under --threads auto)
    try:
        run_one(case)
        return case.name, None
    except KeyboardInterrupt:
        raise
    except Exception as exc:  # one failed case must not stop a long run
        return case.name, record_failure(case.directory(out), case.name, exc)


def run_cases(cases: Iterable[Case], out_dir, run_one: Callable, *, desc: str, progress: bool = True,
              scheduler=None) -> RunSummary:
    """Run every case of ``cases`` without a ``result.json`` under ``out_dir``.

    Args:
        cases: the (sharded) cases, in the order to run them.
        run_one: ``run_one(case)`` runs a case and writes its folder (``result.json`` last); it must be
            picklable (a module-level function or a ``functools.partial`` of one) for a ``scheduler``.
        desc: the progress bar's and the failure lines' prefix (the command's name).
        scheduler: None runs here; a Dask scheduler address or cluster runs on its workers.
    """
    out = Path(out_dir)
    summary = RunSummary()
    todo = []
    for c in cases:
        if (c.directory(out) / RESULT).is_file():
            summary.skipped.append(c.name)
        else:
            todo.append(c)
    bar = None
    if progress and todo:
        from roomlight.core.progress import progress_bar

        bar = progress_bar(total=len(todo), desc=desc, unit="case")
    from roomlight.core.cluster import map_unordered

    try:
        for name, error in map_unordered(partial(_attempt, out=out, run_one=run_one), todo, scheduler):
            if error is None:
                summary.done.append(name)
            else:
                summary.failed[name] = error
                if bar is not None:
                    bar.write(f"{desc}: {name} failed: {error}")
            if bar is not None:
                bar.set_postfix_str(name)
                bar.update()
    finally:
        if bar is not None:
            bar.close()
    return summary
