"""Files a photo fit leaves behind (docs/photo.md, "Outputs").

Per fitted method: ``panorama.exr`` (recovered radiance R, G, B and radial depth Z, the project's
panorama format), ``emitter/`` (the emitter bundle of ``roomlight fit``), ``materials.json``,
``render.exr`` / ``render.png`` (the objects re-rendered with their fitted materials under the
fitted light, from the photograph's camera), ``compare.png`` (photograph | render | error on the
fitted pixels), ``history.jsonl``, ``loss.png`` and ``result.json`` (objective, materials,
settings, timings). Every file is written under a temporary name and renamed into place.
"""

from __future__ import annotations

import json
import math
import os
import shutil
import time
from pathlib import Path

import numpy as np
import torch

from roomlight.core.render.variant import thread_record

__all__ = ["atomic_write", "write_fit_files", "light_view", "RESULT_FORMAT"]

RESULT_FORMAT = "roomlight.photo-fit"


def atomic_write(path: Path, write) -> Path:
    """Call ``write(tmp)`` for a temporary name next to ``path`` (same extension), then rename it to ``path``."""
    path = Path(path)
    tmp = path.with_name(f".{path.stem}.tmp-{os.getpid()}{path.suffix}")
    try:
        write(tmp)
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()
    return path


def _atomic_dir(path: Path, write) -> Path:
    path = Path(path)
    tmp = path.with_name(f".{path.name}.tmp-{os.getpid()}")
    if tmp.exists():
        shutil.rmtree(tmp)
    write(tmp)
    if path.exists():
        old = path.with_name(f".{path.name}.old-{os.getpid()}")
        os.replace(path, old)
        os.replace(tmp, path)
        shutil.rmtree(old)
    else:
        os.replace(tmp, path)
    return path


def _srgb8(linear: np.ndarray) -> np.ndarray:
    from roomlight.core.color import linear_to_srgb

    return np.rint(linear_to_srgb(linear) * 255).astype(np.uint8)


def level_note(level: dict) -> str:
    """One line saying how far the visible room pins the fitted light's level (a ``level_bracket`` record,
    :func:`~roomlight.fitting.photo.room_albedo.level_bracket`)."""
    lo, hi = level["low"], level["high"]
    black, white = level.get("albedo_range", (0.03, 0.9))
    share = f"{1 - 2 * level['trim']:.0%} of the visible room's {level['points']} measured points"
    if not (0 < lo <= hi):
        return (f"level: no one scale of this light keeps {share} between black ({black:g}) and white ({white:g}); "
                "its brightness is the fit's guess")
    where = ("the fitted level lies inside" if lo <= 1 <= hi else
             f"the fitted light is {'dimmer' if lo > 1 else 'brighter'} than that allows")
    return (f"level: {share} stay between black ({black:g}) and white ({white:g}) with this light x{lo:.2f} to "
            f"x{hi:.2f} ({math.log2(hi / lo):.1f} stops); {where}. The photograph does not say where in that "
            "range the truth is (`insert`/`export --reference-albedo` set the level from an object of known albedo)")


def light_view(fit, name: str | None = None):
    """The fitted light of a :class:`~roomlight.fitting.photo.fitter.PhotoFit` as a probes :class:`LightView`."""
    from roomlight.fitting.photo.probes import LightView

    return LightView(name or fit.method, fit.result.light.with_frame(fit.transform.matrix), fit.transform,
                     {lab: fit.materials.bsdf(lab) for lab in fit.materials.labels})


def _write_objects(path: Path, fit) -> None:
    """The objects' meshes in the light's room frame (the frame of ``panorama.exr`` and ``emitter/``),
    each vertex coloured with its object's fitted albedo (linear RGB)."""
    from roomlight.core.io import write_ply

    verts, faces, colours, offset = [], [], [], 0
    albedo = {lab: fit.materials.values().detach()[k, :3].numpy() for k, lab in enumerate(fit.materials.labels)}
    for o in fit.geometry.objects:
        verts.append(fit.transform.points(o.vertices))
        faces.append(o.faces + offset)
        colours.append(np.broadcast_to(albedo[o.label], (len(o.vertices), 3)))
        offset += len(o.vertices)
    write_ply(path, np.concatenate(verts), np.concatenate(faces), vertex_colors=np.concatenate(colours))


def _receivers_json(fit) -> list[dict]:
    """The shadow receivers' fitted materials and how many pixels each was fitted on."""
    r = fit.receivers
    out = fit.model.receivers.to_json()
    for m in out:
        m["fitted_pixels"] = int(((r.labels == m["label"]) & r.mask).sum())
    return out


def write_fit_files(out, fit, case, config, extra: dict | None = None) -> dict[str, Path]:
    """Write one fit's files (module docstring) into ``out``; returns them by role."""
    from roomlight.core.emitter.export import export_emitter
    from roomlight.fitting.inverse.outputs import light_summary, plot_history
    from roomlight.core.io import save_png, write_exr, write_panorama

    t0 = time.perf_counter()
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    r = fit.result
    kind = str(fit.fitter.escene.kind)
    paths: dict[str, Path] = {"history": out / "history.jsonl"}
    meta = {"method": fit.method, "emitter_kind": kind, "source": "roomlight fit-photo"}
    depth = r.depth.numpy() if r.depth is not None else None
    paths["panorama"] = atomic_write(out / "panorama.exr",
                                     lambda p: write_panorama(p, (r.radiance.numpy(), depth), half=False, metadata=meta))
    paths["emitter"] = _atomic_dir(out / "emitter", lambda p: export_emitter(p, r.radiance, r.depth, kind, metadata=meta))
    materials = fit.materials.to_json()
    pixels = {int(lab): int(((fit.geometry.labels == lab) & fit.geometry.loss_mask).sum()) for lab in fit.materials.labels}
    for m in materials:
        m["fitted_pixels"] = pixels[m["label"]]
    paths["materials"] = atomic_write(out / "materials.json",
                                      lambda p: p.write_text(json.dumps({"objects": materials}, indent=2)))

    # The objects re-rendered under the fitted light with their fitted materials (the whole frame).
    es = fit.fitter.escene
    with torch.no_grad():
        es.set_emitter(r.radiance, r.depth)
        es.set_parameters(fit.model.scene_values())
        img = es.render(spp=config.probe_spp, seed=config.seed + 17).numpy()
    paths["render_exr"] = atomic_write(out / "render.exr",
                                       lambda p: write_exr(p, {c: img[..., i] for i, c in enumerate("RGB")}))
    paths["render_png"] = atomic_write(out / "render.png", lambda p: save_png(p, _srgb8(img)))
    target, mask = fit.geometry.target, fit.geometry.loss_mask
    if not mask.any():  # no objects: the render is the light seen through the frame, all of it compared
        mask = np.ones_like(mask)
    err = np.abs(img - target).mean(-1) * mask
    scale = max(float(err.max()), 1e-6)
    err_rgb = (np.stack([err / scale, (err / scale) ** 2, np.zeros_like(err)], -1) * 255).astype(np.uint8)
    strip = np.concatenate([_srgb8(target), _srgb8(img), err_rgb], axis=1)
    paths["compare"] = atomic_write(out / "compare.png", lambda p: save_png(p, strip))
    paths["loss"] = atomic_write(out / "loss.png", lambda p: plot_history(r.history, p, title=f"fit-photo {fit.method}"))
    if fit.geometry.objects:
        paths["objects"] = atomic_write(out / "objects.ply", lambda p: _write_objects(p, fit))

    # Absolute paths: the folder may be used from elsewhere later (``roomlight insert``).
    inputs = {k: str(Path(v).resolve()) if Path(v).exists() else v for k, v in case.files.items()}
    if "depth" not in inputs:  # estimated from the image: keep it, so the fit can be used later (insertion)
        paths["depth"] = atomic_write(out / "depth_estimated.npy", lambda p: np.save(p, case.depth.astype(np.float32)))
        inputs["depth"] = str(paths["depth"].resolve())
    g = fit.geometry
    objects = [{"label": o.label, "mesh_vertices": len(o.vertices), "mesh_triangles": len(o.faces),
                "fitted_pixels": pixels[o.label]} for o in g.objects]
    timings = {**{k: round(v, 3) for k, v in fit.timings.items()}, "outputs": round(time.perf_counter() - t0, 3)}
    summary = {
        "format": RESULT_FORMAT, "version": 1, "method": fit.method, "emitter_kind": kind,
        "objective": {k: float(v) for k, v in fit.objective.items()},
        "best_iteration": r.best_iteration, "best_fixed_seed_loss": r.best_loss, "nonfinite_steps": r.nonfinite_steps,
        "light": light_summary(r.radiance),
        "light_parameters": fit.model.light_model.describe(),
        "materials": materials,
        "objects": objects,
        **({"receivers": _receivers_json(fit)} if fit.model.receivers is not None else {}),
        "camera": {"intrinsics_input": case.intrinsics.intrinsics_dict(), "input_size": [case.height, case.width],
                   "render_size": [g.intrinsics.height, g.intrinsics.width],
                   "intrinsics_render": g.intrinsics.intrinsics_dict(),
                   "depth_kind": case.depth_kind, "pitch_deg": case.pitch_deg, "roll_deg": case.roll_deg},
        "transform": fit.transform.to_dict(),
        "initial": fit.initial,
        "containment": fit.containment,
        "level_bracket": fit.level_bracket,
        "inputs": inputs,
        "settings": config.to_dict(),
        "timings": timings,
        "threads": thread_record(),
        "notes": list(case.notes),
        **(extra or {}),
        "files": {k: str(v.relative_to(out)) for k, v in paths.items()},
    }
    paths["result"] = out / "result.json"
    summary["files"]["result"] = "result.json"
    atomic_write(paths["result"], lambda p: p.write_text(json.dumps(summary, indent=2)))
    return paths
