"""How many CPUs this process may use and how many other processes keep busy (``/proc/stat``).

The measurements behind the thread policy (:mod:`roomlight.cli.threads` applies it when a command
starts; under ``--threads auto``, :func:`roomlight.core.render.variant.recheck_threads` measures the load
again between long phases).
"""

from __future__ import annotations

import os
import time

__all__ = ["ENV_THREADS", "ENV_THREADS_AUTO", "available_cpus", "busy_cpus", "measured_threads"]

#: The thread count of torch and Dr.Jit (``--threads`` sets it).
ENV_THREADS = "ROOMLIGHT_THREADS"
#: "1" when :data:`ENV_THREADS` was measured from the load (``--threads auto``): only then do long commands
#: measure the load again between their phases and follow it.
ENV_THREADS_AUTO = "ROOMLIGHT_THREADS_AUTO"


def available_cpus() -> int:
    """CPUs this process may run on (its affinity mask; the machine's count where that is unknown)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):  # not on Linux
        return max(1, os.cpu_count() or 1)


def _own_ticks() -> int:
    """Clock ticks of CPU time this process has used (all threads; user + system)."""
    with open("/proc/self/stat") as f:
        fields = f.read().rpartition(")")[2].split()
    return int(fields[11]) + int(fields[12])  # utime, stime (fields 14 and 15 of the line)


def busy_cpus(interval: float = 0.05, exclude_self: bool = False) -> float:
    """CPUs kept busy over ``interval`` seconds by all processes, or by all others with ``exclude_self``
    (this process's threads may still be spinning down from its last parallel region). 0 where
    ``/proc`` cannot be read."""
    def snapshot():
        with open("/proc/stat") as f:
            values = [int(v) for v in f.readline().split()[1:9]]
        own = _own_ticks() if exclude_self else 0
        return sum(values), values[3] + values[4], own  # total, idle + iowait, this process

    try:
        total0, idle0, own0 = snapshot()
        time.sleep(interval)
        total1, idle1, own1 = snapshot()
    except (OSError, ValueError, IndexError):
        return 0.0
    if total1 <= total0:
        return 0.0
    cpus = os.cpu_count() or 1
    # /proc/stat counts every CPU's ticks, /proc/self/stat this process's on any CPU: the share of the
    # machine this process used is its ticks over the total ticks of all CPUs.
    busy = 1.0 - (idle1 - idle0) / (total1 - total0) - (own1 - own0) / (total1 - total0)
    return max(0.0, busy) * cpus


def measured_threads(exclude_self: bool = False) -> int:
    """:func:`available_cpus` less the CPUs other processes keep busy right now, at least 1."""
    return max(1, available_cpus() - int(busy_cpus(exclude_self=exclude_self) + 0.5))
