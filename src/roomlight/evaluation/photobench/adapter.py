"""The one place the photo benchmark calls the photo fit (``roomlight fit-photo``, :mod:`roomlight.fitting.photo`).

:func:`fit_photo_case` fits one method to one photo case folder and returns what the scoring
needs, in the benchmark's own terms (plain numpy, no photo-fit classes). Everything else of the
benchmark (building, scoring, running, reporting) only knows this function's signature and the
dict it returns, so a change of the photo fit's API is absorbed here.

``roomlight.fitting.photo`` is imported when a fit is asked for, not at import time: building the
benchmark and scoring its oracles do not load the photo fit.
"""

from __future__ import annotations

import time
from pathlib import Path

from roomlight.errors import RoomlightError
from roomlight.fitting.methods import ESTIMATE_ROWS, PHOTO, methods_for
from roomlight.fitting.methods import method as method_record

__all__ = ["PHOTO_FIT_METHODS", "finished_fit", "fit_photo_case"]

#: Every method name the benchmark can fit: those of ``roomlight fit-photo`` and the variants of ``prior``
#: with a fixed start (``fit-photo --init``), the rows that split the photo fit's gap. (``prior`` itself
#: starts as fit-photo does by default: from the view encoder when the prior has one.) Not the rows of
#: ``roomlight estimate``, which fit nothing through fit-photo.
PHOTO_FIT_METHODS = tuple(m for m in methods_for(PHOTO, fitted=True) if m not in ESTIMATE_ROWS)


def fit_photo_case(case_dir, method: str, preset: str, out_dir, model=None, progress: bool = False,
                   overrides: dict | None = None) -> dict:
    """Fit ``method`` to the photo case ``case_dir`` with the fit-photo ``preset``; write the fit's
    files (``panorama.exr``, ``emitter/``, ``materials.json``, ``result.json``, ...) to ``out_dir``.

    Args:
        case_dir: a photo case folder (image, depth, mask, camera.json); ``truth/`` is not read.
        method: one of :data:`PHOTO_FIT_METHODS`.
        preset: a fit-photo preset (``paper``, ``fast``).
        model: the prior (a ``PanoVAE``) for the prior methods.
        overrides: fit-photo settings that replace the preset's (``{"iterations": 300}``).
    Returns:
        ``{"radiance": (H, W, 3) float32, "depth": (H, W) float32 or None, "emitter_kind": str,
        "light_from_camera": (4, 4) float64 similarity (camera frame -> the light's frame:
        p = s R p_camera + t), "materials": {label: {"albedo", "roughness", "metallic"}},
        "seconds": fit time}``.
    """
    from roomlight.fitting.photo import case as case_mod
    from roomlight.fitting.photo import config as config_mod
    from roomlight.fitting.photo import fitter as fitter_mod

    if method not in PHOTO_FIT_METHODS:
        raise RoomlightError(f"unknown photo method {method!r}; choose one of {', '.join(PHOTO_FIT_METHODS)}")
    t0 = time.perf_counter()
    overrides = dict(overrides or {})
    record = method_record(method)
    if record.init is not None:
        method, overrides["init"] = record.fitted_as, record.init
    config = config_mod.photo_config(preset, **overrides)
    case = case_mod.load_photo(str(case_dir), min_object_fraction=config.min_object_fraction)
    out = Path(out_dir)
    fit = fitter_mod.fit_photo(case, method, config, model=model, out_dir=out, progress=progress)
    return finished_fit(fit, case, config, out, t0)


def finished_fit(fit, case, config, out_dir, t0: float) -> dict:
    """Write a finished photo fit's files to ``out_dir``, drop its resumable state, and return the dict
    :func:`fit_photo_case` returns (``t0``: when the fit began, for its time where it recorded none).
    For a fit function of its own (``run_photo_benchmark(fit=...)``) that calls ``fit_photo`` itself."""
    from roomlight.fitting.photo import fitter as fitter_mod
    from roomlight.fitting.photo import outputs as outputs_mod

    out = Path(out_dir)
    outputs_mod.write_fit_files(out, fit, case, config)
    (out / fitter_mod.STATE_FILE).unlink(missing_ok=True)  # finished: the outputs are the result
    radiance, depth = fit.result.light.to_numpy()
    return {"radiance": radiance, "depth": depth,
            "emitter_kind": str(fit.fitter.escene.kind), "light_from_camera": fit.transform.matrix,
            "materials": {int(e["label"]): {"albedo": e["albedo"], "roughness": e["roughness"],
                                            "metallic": e["metallic"]} for e in fit.materials.to_json()},
            "seconds": float(fit.timings.get("fit", time.perf_counter() - t0))}
