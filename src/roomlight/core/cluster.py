"""Spreading independent work items over a Dask cluster, or running them here one after another.

``roomlight synth --scheduler ADDRESS`` and ``roomlight bench run --scheduler ADDRESS`` send each
item (a room seed, a benchmark case) to the workers of a running Dask scheduler
(``dask scheduler`` + ``dask worker ADDRESS`` on each machine; every worker needs roomlight
installed and the output folder on a shared file system). Items write their own files, exactly
as in a serial run, so an interrupted run resumes with or without a cluster. Dask is an optional
dependency: ``pip install 'roomlight[dask]'``.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator

from roomlight.errors import RoomlightError

__all__ = ["map_unordered"]


def map_unordered(fn: Callable, items: Iterable, scheduler=None) -> Iterator:
    """``fn(item)`` for every item, yielded as each finishes.

    ``scheduler``: None runs here, in order; an address (``tcp://host:8786``) or a
    ``distributed`` cluster object (e.g. a ``LocalCluster``) runs on that cluster. ``fn`` and the
    items must be picklable; ``fn`` should catch its own errors (one that raises stops the loop).
    """
    items = list(items)
    if scheduler is None:
        for item in items:
            yield fn(item)
        return
    try:
        from distributed import Client, as_completed
    except ImportError:
        raise RoomlightError("--scheduler needs Dask's distributed scheduler: pip install 'roomlight[dask]'") from None
    try:
        client = Client(scheduler, timeout="30s", set_as_default=False)
    except (OSError, TimeoutError) as exc:
        raise RoomlightError(f"--scheduler {scheduler}: cannot reach the Dask scheduler ({exc})") from None
    with client:
        futures = client.map(fn, items, pure=False)
        for future in as_completed(futures, loop=client.loop):
            yield future.result()
