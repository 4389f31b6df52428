"""``roomlight fit-photo`` from start to end: fit the method (and the compared baselines), write
each fit's files, then the probes figure showing every fitted light side by side.

Output layout (docs/photo.md): the main method's files in ``out/``, each compared method's in
``out/compare/<method>/``, and ``out/probes.png`` + ``out/probes.json`` for all of them. When
nothing else is compared with a 2.5D light, the figure adds the same recovered radiance shown
as an env map ("... at infinity"), so the figure always shows what position-dependence adds.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass, field
from pathlib import Path

from roomlight.fitting.photo.config import PhotoFitConfig
from roomlight.fitting.photo.fitter import STATE_FILE, PhotoFit, fit_photo

__all__ = ["PhotoRun", "run_photo"]


@dataclass
class PhotoRun:
    """Every fit of one ``fit-photo`` run, its output folders and timings (seconds)."""

    fits: list[PhotoFit]
    folders: list[Path]
    timings: dict = field(default_factory=dict)


def run_photo(case, method: str, config: PhotoFitConfig, out, model=None, compare=(), progress: bool = True,
              resume: bool = True, say=print) -> PhotoRun:
    """Fit ``method`` and every method of ``compare`` to ``case``, write all outputs into ``out``.

    Args:
        model: the prior (a PanoVAE) when a prior method is among them.
        say: called with one line per finished step (e.g. ``click.echo``).
    """
    from roomlight.fitting.inverse.outputs import recorded_light_note
    from roomlight.core.light import Light
    from roomlight.fitting.photo.outputs import atomic_write, level_note, light_view, write_fit_files
    from roomlight.fitting.photo.probes import LightView, choose_probe_sites, probe_figure, render_probes

    t_start = time.perf_counter()
    out = Path(out)  # created by the first fit, once its inputs are accepted
    methods = [method] + [m for m in dict.fromkeys(compare) if m != method]
    fits, folders = [], []
    for m in methods:
        folder = out if m == method else out / "compare" / m
        fit = fit_photo(case, m, config, model=model, out_dir=folder, progress=progress, resume=resume)
        files = write_fit_files(folder, fit, case, config, extra={"compared_with": [x for x in methods if x != m]})
        (folder / STATE_FILE).unlink(missing_ok=True)  # finished: the outputs are the result
        say(f"{m}: best iteration {fit.result.best_iteration} (fixed-seed loss {fit.result.best_loss:.4g}) "
            f"in {fit.timings['fit']:.1f} s -> {folder}")
        if fit.level_bracket is not None:
            say(f"{m}: {level_note(fit.level_bracket)}")
        note = recorded_light_note(files["result"])
        if note:
            say(f"{m}: {note}")
        fits.append(fit)
        folders.append(folder)

    t0 = time.perf_counter()
    main = fits[0]
    sites = choose_probe_sites(_probe_surfaces(main.geometry), config.probe_count, config.probe_size,
                               main.geometry.intrinsics)
    views = [light_view(f) for f in fits]
    if len(fits) == 1 and main.result.depth is not None:
        v = views[0]
        views.append(LightView(f"{main.method} at infinity", Light(v.light.radiance, None, "envmap", v.light.frame),
                               v.transform, v.bsdfs))
    rows = []
    for v in views:
        rows.append((v.name, render_probes(v, main.geometry.objects, sites, main.geometry.intrinsics,
                                           spp=config.probe_spp, resolution=config.probe_resolution, seed=config.seed)))
    atomic_write(out / "probes.png", lambda p: probe_figure(rows, p, photo=main.geometry.target))
    atomic_write(out / "probes.json", lambda p: p.write_text(json.dumps(
        {"sites": [s.to_dict() for s in sites], "rows": [v.name for v in views],
         "columns": ["view with mirror probes"] + [f"{mat} probe {k}" for mat in ("mirror", "diffuse")
                                                   for k in range(len(sites))]}, indent=2)))
    timings = {"probes": time.perf_counter() - t0, "total": time.perf_counter() - t_start}
    say(f"probes: {len(sites)} positions under {len(views)} light(s) in {timings['probes']:.1f} s -> {out / 'probes.png'}")
    return PhotoRun(fits, folders, timings)


def _probe_surfaces(geometry) -> list:
    """Where the probes rest: the objects, or, in a photo without objects, the visible room itself (its
    whole depth mesh, as one surface)."""
    if geometry.objects:
        return geometry.objects
    import numpy as np

    from roomlight.fitting.photo.unproject import object_mesh

    return [object_mesh(geometry.mesh, np.ones(geometry.mesh.shape, np.int32), 1, None)]
