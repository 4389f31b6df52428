"""``roomlight info``: versions, the Mitsuba variant that will be used, and the torch device."""

from __future__ import annotations

import platform

import click


@click.command("info")
def command():
    """Print versions, the Mitsuba variant roomlight will use, and the torch device.

    When Mitsuba's CPU backend cannot start (LLVM missing or older than 16) this says why and
    how to fix it.
    """
    import numpy
    import torch

    from roomlight import __version__
    from roomlight.errors import BackendError
    from roomlight.core.render.variant import choose_variant, cuda_available, llvm_status

    rows = [("roomlight", __version__), ("python", platform.python_version()),
            ("numpy", numpy.__version__), ("torch", torch.__version__)]
    try:
        import drjit
        import mitsuba

        rows += [("mitsuba", mitsuba.__version__), ("drjit", drjit.__version__)]
    except ImportError as exc:  # pragma: no cover - broken install
        rows.append(("mitsuba", f"NOT IMPORTABLE ({exc})"))
        mitsuba = None
    if torch.cuda.is_available():
        dev = f"cuda ({torch.cuda.get_device_name(0)})"
    else:
        dev = f"cpu ({torch.get_num_threads()} threads)"
    rows.append(("torch device", dev))
    problems = []
    if mitsuba is not None:
        ok, why = llvm_status()
        rows.append(("LLVM backend", ("ok, " if ok else "UNUSABLE: ") + why))
        rows.append(("CUDA backend", "ok" if cuda_available() else "not available"))
        try:
            rows.append(("mitsuba variant", choose_variant()))
        except BackendError as exc:
            rows.append(("mitsuba variant", "NONE"))
            problems.append(str(exc))
    width = max(len(k) for k, _ in rows)
    for k, v in rows:
        click.echo(f"{k:<{width}}  {v}")
    for p in problems:
        click.echo(f"\nproblem: {p}", err=True)
    if problems:
        raise SystemExit(1)
