"""Choosing and activating the Mitsuba variant (docs/conventions.md, "Mitsuba on CPU machines").

The choice is made in one function, on first use, never at import time: ``cuda_ad_rgb`` when a
CUDA device is usable, else ``llvm_ad_rgb`` (CPU). ``ROOMLIGHT_VARIANT`` overrides it.

Dr.Jit >= 1.5 needs LLVM >= 16 for its CPU backend. With LLVM 15 the process *aborts* inside
LLVM (``Cannot select ... fminimum``) on the first kernel, so the version is checked before the
variant is activated and an actionable :class:`BackendError` is raised instead.
"""

from __future__ import annotations

import os
import sys

from roomlight.errors import BackendError

__all__ = ["MIN_LLVM", "ENV_DETERMINISTIC", "ENV_PARALLEL_BACKWARD", "serial_backward", "worker_count", "recheck_threads", "thread_record", "deterministic", "llvm_status", "cuda_available", "choose_variant",
           "ensure_variant", "mitsuba", "torch_device"]

MIN_LLVM = (16, 0, 0)
LLVM_FIX = (
    "install LLVM 16 or newer, e.g. `apt-get install libllvm19` (or run `make setup`); "
    "if it lives in a non-standard place set DRJIT_LIBLLVM_PATH=/path/to/libLLVM.so"
)

_active: str | None = None
#: Dr.Jit workers outside adjoint passes, set when the LLVM variant is activated.
_workers: int | None = None


def llvm_status() -> tuple[bool, str]:
    """(usable, description) of Dr.Jit's CPU backend, without risking an LLVM abort."""
    import drjit as dr

    version = tuple(dr.detail.llvm_version())
    if version[0] < 0:
        return False, "Dr.Jit found no usable libLLVM (" + LLVM_FIX + ")"
    text = ".".join(str(v) for v in version)
    if version < MIN_LLVM:
        return False, f"libLLVM {text} is too old for Dr.Jit's CPU backend (needs >= 16; {LLVM_FIX})"
    return True, f"libLLVM {text}"


def cuda_available() -> bool:
    """True when Dr.Jit can drive a CUDA device."""
    import drjit as dr

    try:
        return bool(dr.has_backend(dr.JitBackend.CUDA))
    except Exception:  # pragma: no cover - depends on the driver
        return False


def choose_variant(prefer: str | None = None) -> str:
    """Name of the Mitsuba variant to use: ``prefer``, ``$ROOMLIGHT_VARIANT``, CUDA, else LLVM.

    Raises :class:`BackendError` when no differentiable backend can run here.
    """
    want = prefer or os.environ.get("ROOMLIGHT_VARIANT") or None
    if want in (None, "", "auto"):
        if cuda_available():
            return "cuda_ad_rgb"
        want = "llvm_ad_rgb"
    if want.startswith("llvm"):
        ok, why = llvm_status()
        if not ok:
            raise BackendError(f"Mitsuba variant {want!r} cannot start: {why}")
    elif want.startswith("cuda") and not cuda_available():
        raise BackendError(f"Mitsuba variant {want!r} needs a CUDA GPU and driver, and none is usable here")
    return want


def ensure_variant(prefer: str | None = None) -> str:
    """Activate (once) and return the Mitsuba variant; later calls return the active one.

    A different explicit ``prefer`` after activation switches variants (objects built under the
    old variant must not be mixed with the new one).
    """
    global _active
    import mitsuba as mi

    if _active is not None and (prefer is None or prefer == _active):
        return _active
    name = choose_variant(prefer)
    if name not in mi.variants():
        raise BackendError(f"this Mitsuba build has no variant {name!r}; available: {', '.join(mi.variants())}")
    mi.set_variant(name)
    _active = name
    threads = os.environ.get("ROOMLIGHT_THREADS", "")
    if deterministic() and name.startswith("llvm"):
        # Dr.Jit's workers add gradients (and samples) into shared texels and vertices in whatever
        # order they reach them, which changes the last bits run to run; one worker fixes the order.
        import drjit as dr

        dr.set_thread_count(1)
    elif threads.isdigit() and name.startswith("llvm"):
        # The command line's thread policy (roomlight.cli.threads). Two workers at least otherwise.
        import drjit as dr

        dr.set_thread_count(max(2, int(threads)))
    if name.startswith("llvm"):
        import drjit as dr

        global _workers
        _workers = dr.thread_count()
    return name


#: Set to 1 (``roomlight --deterministic``) for bit-identical renders and fits on the CPU.
ENV_DETERMINISTIC = "ROOMLIGHT_DETERMINISTIC"
#: Set to 1 to let the adjoint (backward) pass of a differentiable render use every Dr.Jit worker:
#: faster where the adjoint dominates, but its gradients then vary in their last bits run to run.
ENV_PARALLEL_BACKWARD = "ROOMLIGHT_PARALLEL_BACKWARD"


def _env_flag(name: str) -> bool:
    """Whether the environment variable ``name`` is set to a yes (1, true, yes, on; any case)."""
    return os.environ.get(name, "").strip().lower() in ("1", "true", "yes", "on")


def serial_backward() -> bool:
    """Whether differentiable renders on the CPU run their adjoint pass on one Dr.Jit worker (the
    default): the primal render is bit-identical run to run with any number of workers, the adjoint
    is not (workers scatter-add gradients into shared texels in varying order), so serialising only
    the adjoint makes fits repeatable at a fraction of the cost of one worker throughout."""
    return ensure_variant().startswith("llvm") and not _env_flag(ENV_PARALLEL_BACKWARD)


def worker_count() -> int:
    """Dr.Jit's worker count outside adjoint passes (the thread policy's, or Dr.Jit's default)."""
    import drjit as dr

    ensure_variant()
    return _workers if _workers is not None else dr.thread_count()


def recheck_threads(note=None) -> int | None:
    """Measure the load again and follow it: between the long phases of a command (benchmark cases,
    training validations) the other processes may have changed. Only when asked for (``--threads auto``,
    which the ``roomlight`` program marks, :data:`roomlight.core.cpu.ENV_THREADS_AUTO`); the default count,
    one given with ``--threads N`` / ``$ROOMLIGHT_THREADS``, and ``--deterministic`` stay as they are.

    Sets torch's threads and Dr.Jit's workers (at least two) to the CPUs this process may use less
    those other processes keep busy now (this process's own threads excluded); returns the new count
    when it changed, else None. ``note`` receives one line when it changes.
    """
    from roomlight.core.cpu import ENV_THREADS, ENV_THREADS_AUTO, measured_threads

    if os.environ.get(ENV_THREADS_AUTO) != "1" or deterministic():
        return None
    n = measured_threads(exclude_self=True)
    if str(n) == os.environ.get(ENV_THREADS):
        return None
    os.environ[ENV_THREADS] = os.environ["OMP_NUM_THREADS"] = str(n)
    if "torch" in sys.modules:
        sys.modules["torch"].set_num_threads(n)
    global _workers
    if _active is not None and _active.startswith("llvm"):
        import drjit as dr

        dr.set_thread_count(max(2, n))
        _workers = dr.thread_count()
    if note is not None:
        note(f"the load changed: now {n} thread(s) for torch and {max(2, n)} for Mitsuba")
    return n


def thread_record() -> dict:
    """The threads a result is being computed with, for its record: CPU results depend on them in their
    last bits (torch splits its float sums by thread), so two records that differ there may differ in
    their numbers too (docs/troubleshooting.md, "The same command twice gives the same numbers").

    ``torch``: torch's intra-op threads; ``mitsuba``: Dr.Jit's CPU workers outside adjoint passes (None
    before the CPU variant is active, or on a GPU); ``parallel_backward``: adjoint passes on every worker
    (``ROOMLIGHT_PARALLEL_BACKWARD=1``, whose gradients vary in their last bits run to run) instead of one;
    ``policy``: ``auto`` when the count follows the load (``--threads auto``), else ``fixed``;
    ``deterministic``: ``--deterministic``. Activates nothing.
    """
    import torch

    from roomlight.core.cpu import ENV_THREADS_AUTO

    cpu_variant = _active is not None and _active.startswith("llvm")
    return {"torch": int(torch.get_num_threads()), "mitsuba": worker_count() if cpu_variant else None,
            "parallel_backward": _env_flag(ENV_PARALLEL_BACKWARD),
            "policy": "auto" if os.environ.get(ENV_THREADS_AUTO) == "1" else "fixed",
            "deterministic": deterministic()}


def deterministic() -> bool:
    """Whether ``$ROOMLIGHT_DETERMINISTIC`` asks for bit-identical results (Dr.Jit on one CPU thread)."""
    return _env_flag(ENV_DETERMINISTIC)


def mitsuba():
    """The ``mitsuba`` module with a differentiable variant active (see :func:`ensure_variant`)."""
    import mitsuba as mi

    ensure_variant()
    return mi


def torch_device() -> str:
    """The torch device whose tensors Dr.Jit's active backend shares without copies:
    ``cuda`` for the CUDA variants, ``cpu`` for LLVM."""
    return "cuda" if ensure_variant().startswith("cuda") else "cpu"
