"""Thread policy of the command line: how many threads torch and Dr.Jit use, and how they wait.

A roomlight command alternates between Mitsuba (Dr.Jit's thread pool) and torch (OpenMP). Left
alone, OpenMP's worker threads spin at 100 % between parallel regions (GNU OpenMP spins for
about 300,000 iterations before sleeping), which steals the cores from Dr.Jit's phase and, on a
machine where anything else runs, from the other process; and torch sizes its pool by the
machine's cores, not the ones this process may run on (a container, ``taskset``, a batch slot).
The policy, applied once when ``roomlight`` starts:

- ``OMP_WAIT_POLICY=PASSIVE`` (and ``KMP_BLOCKTIME=0`` for Intel's OpenMP) when other processes keep
  at least half a CPU busy: idle threads sleep at once. On an idle machine OpenMP keeps its short spin,
  which is faster there. Set before torch is imported, unless the user already set it;
- threads: ``--threads N``, else ``$ROOMLIGHT_THREADS``, else the CPUs this process may use
  (``os.sched_getaffinity``), for torch and for Dr.Jit alike. The count never follows the load by
  default: torch splits its float reductions by thread, so a count taken from the load would make the
  same command give other numbers beside another job. ``--threads auto`` (``ROOMLIGHT_THREADS=auto``)
  asks for that trade: the CPUs less those other processes keep busy, measured over 50 ms when the
  program starts (``/proc/stat``) and again between a long command's phases, at least one; faster
  beside other work where torch dominates, repeatable only on a machine in the same state.

``benchmarks/bench_threads.py`` measures the policy against torch's defaults, idle and next to a
busy process (README, Troubleshooting).
"""

from __future__ import annotations

import os
import sys

from roomlight.errors import RoomlightError

__all__ = ["ENV_THREADS", "AUTO", "available_cpus", "prepare_environment", "thread_count", "apply_thread_policy",
           "default_threads", "busy_cpus", "measured_threads"]

from roomlight.core.cpu import ENV_THREADS, ENV_THREADS_AUTO, available_cpus, busy_cpus, measured_threads  # noqa: F401


#: Other processes keeping at least this many CPUs busy make OpenMP's threads sleep when idle.
BUSY_THRESHOLD = 0.5


def prepare_environment(busy: float | None = None) -> None:
    """Passive waiting for OpenMP threads when other processes keep a CPU busy (``busy``: CPUs, measured
    now by default); on an idle machine OpenMP keeps its short spin, which is faster there. Must run
    before torch is imported to take effect; a value the user set is kept."""
    if busy is None:
        busy = busy_cpus()
    if busy >= BUSY_THRESHOLD:
        os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")
        os.environ.setdefault("KMP_BLOCKTIME", "0")


#: The thread count that follows the machine's load (``--threads auto``).
AUTO = "auto"


def _requested(option: int | str | None) -> str:
    """The thread request in force: ``option``, else ``$ROOMLIGHT_THREADS``, as text ('' when neither)."""
    return str(option).strip() if option is not None else os.environ.get(ENV_THREADS, "").strip()


def parse_thread_request(text: str) -> int | str:
    """A thread request as written (``--threads`` or ``$ROOMLIGHT_THREADS``): a positive whole number, or
    :data:`AUTO`. Raises ValueError, with a message for the user, on anything else."""
    raw = str(text).strip()
    if raw.lower() == AUTO:
        return AUTO
    try:
        n = int(raw)
    except ValueError:
        raise ValueError(f"{text!r} is neither a positive whole number nor {AUTO!r}") from None
    if n < 1:
        raise ValueError(f"{n} is not a positive number of threads")
    return n


def thread_count(option: int | str | None = None) -> int:
    """``option``, else ``$ROOMLIGHT_THREADS``, else :func:`available_cpus`; ``auto`` (either way) is
    :func:`measured_threads`, the CPUs less those other processes keep busy now."""
    raw = _requested(option)
    if not raw:
        return available_cpus()
    try:
        request = parse_thread_request(raw)
    except ValueError:
        where = "--threads" if option is not None else ENV_THREADS
        raise RoomlightError(f"{where}={raw!r}: expected a positive whole number of threads, or 'auto'") from None
    return measured_threads() if request == AUTO else request


def apply_thread_policy(option: int | str | None = None) -> int | None:
    """Apply an explicit thread count (``option``, else ``$ROOMLIGHT_THREADS``; a number or ``auto``);
    returns it, or None when neither is given (then no count is set).

    The count is exported as ``$ROOMLIGHT_THREADS`` and ``$OMP_NUM_THREADS`` so that worker
    processes and the Mitsuba setup (:func:`roomlight.core.render.variant.ensure_variant`) use the
    same number. The ``roomlight`` program sets ``$ROOMLIGHT_THREADS`` to :func:`available_cpus`
    when it starts (see :func:`default_threads`), so a command always runs under the policy; code
    that calls the command group in-process keeps its own settings unless it asks.

    ``$ROOMLIGHT_THREADS_AUTO`` marks the count as measured from the load, so that long commands measure
    again between their phases (:func:`roomlight.core.render.variant.recheck_threads`); it is set when
    ``auto`` is asked for and removed otherwise, so that no re-measurement changes a fixed count mid-run
    and, with it, the order of torch's float reductions (a resumed training run would then differ from
    an uninterrupted one), and no earlier ``auto`` outlives its command.
    """
    requested = _requested(option)
    if requested.lower() != AUTO:
        os.environ.pop(ENV_THREADS_AUTO, None)
    if not requested:
        return None
    n = thread_count(option)
    os.environ[ENV_THREADS] = os.environ["OMP_NUM_THREADS"] = str(n)
    if requested.lower() == AUTO:
        os.environ[ENV_THREADS_AUTO] = "1"
    if "torch" in sys.modules:  # torch reads OMP_NUM_THREADS only when it loads
        sys.modules["torch"].set_num_threads(n)
    return n


def default_threads() -> None:
    """``$ROOMLIGHT_THREADS`` defaults to :func:`available_cpus`, whatever else runs: the same command
    then gives the same numbers beside another job as on an idle machine. ``ROOMLIGHT_THREADS=auto`` is
    left for :func:`apply_thread_policy` to measure."""
    if not os.environ.get(ENV_THREADS, "").strip():
        os.environ[ENV_THREADS] = str(available_cpus())
