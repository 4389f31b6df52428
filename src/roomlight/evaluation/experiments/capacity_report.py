"""The capacity experiment's tables, verdict and figures (``OUT/capacity.md``, ``.json``, ``figures/``).

Per room and material, the paper's cell for an emitter is the min--max over the three capture
points of the probe-averaged RMSE; the noise floor is the probe-averaged RMSE between the two
ground-truth renders. Over rooms:

- each end of the min--max cell is averaged over rooms, with a 95 % percentile-bootstrap interval
  of that mean (rooms resampled; :func:`roomlight.core.stats.bootstrap_mean_interval`);
- the ratio environment map / 2.5D light of a room is the ratio of their errors averaged over the
  capture points; rooms are summarised by the geometric mean of the ratios (bootstrap interval
  on the logs), their range and the number of rooms where the ratio exceeds 1 and lies in [2, 5]
  (the paper's claim).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from roomlight.core.stats import RESAMPLES, bootstrap_mean_interval
from roomlight.evaluation.experiments.capacity_record import KIND_LABELS, KINDS, MATERIAL_LABELS, PAPER_RATIO, room_cells

__all__ = ["summarize_capacity", "capacity_markdown", "write_capacity_report"]



def _interval(values) -> dict:
    a = np.asarray(values, np.float64)
    lo, hi = bootstrap_mean_interval(a)
    return {"mean": float(a.mean()), "ci95": [lo, hi], "n": int(a.size)}


def _ratio_stats(ratios) -> dict:
    r = np.asarray(ratios, np.float64)
    logs = np.log(r)
    lo, hi = bootstrap_mean_interval(logs)
    a, b = PAPER_RATIO
    return {"geomean": float(np.exp(logs.mean())), "ci95": [float(np.exp(lo)), float(np.exp(hi))],
            "min": float(r.min()), "max": float(r.max()), "n": int(r.size),
            "above_1": int((r > 1).sum()), "in_paper_range": int(((r >= a) & (r <= b)).sum()),
            "per_room": r.tolist()}


def summarize_capacity(records: list[dict]) -> dict:
    """The summary of a run: the one-room cells (first record) and the aggregate over all rooms."""
    cells = [room_cells(r) for r in records]
    materials = list(records[0]["rmse"])
    agg: dict = {}
    ratios: dict = {}
    for material in materials:
        m = {"noise_floor": _interval([c[material]["noise_floor"] for c in cells]),
             "mesh_noise": _interval([c[material]["mesh_noise"] for c in cells])}
        for kind in KINDS:
            m[kind] = {"min": _interval([c[material][kind][0] for c in cells]),
                       "max": _interval([c[material][kind][1] for c in cells])}
        agg[material] = m
        ratios[material] = {
            "envmap_over_mesh": _ratio_stats([c[material]["envmap_mean"] / c[material]["mesh_mean"] for c in cells]),
            "sphere_over_mesh": _ratio_stats([c[material]["sphere_mean"] / c[material]["mesh_mean"] for c in cells]),
            "mesh_over_noise": _ratio_stats([c[material]["mesh_mean"] / c[material]["noise_floor"] for c in cells]),
        }
    return {"rooms": [r["name"] for r in records], "materials": materials, "one_room": {
        "name": records[0]["name"], "cells": cells[0]}, "per_room": dict(zip([r["name"] for r in records], cells)),
        "aggregate": agg, "ratios": ratios}


def _f(x: float) -> str:
    return f"{x:.3f}" if abs(x) < 100 else f"{x:.1f}"


def _verdict(summary: dict) -> list[str]:
    """Plain sentences on the paper's claim, one per material, from the measured ratios."""
    a, b = PAPER_RATIO
    lines = []
    for material in summary["materials"]:
        s = summary["ratios"][material]["envmap_over_mesh"]
        lo, hi = s["ci95"]
        if lo >= a and hi <= b:
            where = f"inside the paper's {a:g}–{b:g}×"
        elif hi < 1:
            where = "the environment map is *better* than the 2.5D light here, against the paper"
        elif hi < a:
            where = f"below the paper's {a:g}–{b:g}× (the 2.5D light helps less than reported)"
        elif lo > b:
            where = f"above the paper's {a:g}–{b:g}× (the 2.5D light helps more than reported)"
        else:
            where = f"overlapping the paper's {a:g}–{b:g}× without lying inside it"
        lines.append(f"- **{MATERIAL_LABELS.get(material, material)}**: environment map / 2.5D light = "
                     f"{s['geomean']:.2f}× (geometric mean over {s['n']} rooms, 95 % interval {lo:.2f}–{hi:.2f}, "
                     f"range {s['min']:.2f}–{s['max']:.2f}); the 2.5D light is better in {s['above_1']}/{s['n']} "
                     f"rooms and within {a:g}–{b:g}× in {s['in_paper_range']}/{s['n']}: {where}.")
    return lines


def capacity_markdown(summary: dict, settings: dict, wall_seconds: float | None = None,
                      skipped: dict | None = None, room_seconds: float | None = None, reused: int = 0) -> str:
    """The report: settings, the one-room table in the paper's layout, the aggregate with
    intervals, the ratios and the verdict."""
    mats = summary["materials"]
    head = "| Emitter | " + " | ".join(MATERIAL_LABELS.get(m, m) for m in mats) + " |"
    rule = "|---|" + "|".join([":---:"] * len(mats)) + "|"
    H = settings["pano_height"]
    label = {k: KIND_LABELS[k] + (f", {H} × {2 * H}" if k == "mesh" else "") for k in KINDS}
    n = len(summary["rooms"])
    lines = ["# Capacity of a single 2.5D area light", "",
             f"{n} room{'s' if n != 1 else ''} ({', '.join(summary['rooms'])}); probes of radius "
             f"{settings['probe_radius']} m seen at {settings['image_size']} × {settings['image_size']} pixels; "
             f"panoramas {H} × {2 * H} at {settings['pano_spp']} spp; ground truth {settings['gt_spp']} spp, "
             f"emitter renders {settings['emitter_spp']} spp; panorama paths {settings['max_depth']} bounces, "
             f"probe renders one more; seed {settings['seed']}.",
             "Linear RMSE over each probe's pixels, in units where the room's midpoint panorama has "
             "log-average luminance 1. Cells: min–max over the three capture points (centre of A, centre of "
             "B, midpoint) of the RMSE averaged over the three probes.", ""]
    if wall_seconds is not None:
        text = f"Wall time of this call: {wall_seconds / 60:.1f} min"
        if reused:
            text += f" ({reused} room{'s' if reused != 1 else ''} measured earlier and reused)"
        if room_seconds is not None:
            text += f"; the rooms' own measuring times add up to {room_seconds / 60:.1f} min"
        lines += [text + ".", ""]
    one = summary["one_room"]["cells"]
    lines += [f"## One room ({summary['one_room']['name']})", "", head, rule,
              "| Noise floor | " + " | ".join(_f(one[m]["noise_floor"]) for m in mats) + " |"]
    for kind in KINDS:
        lines.append(f"| {label[kind]} | " + " | ".join(f"{_f(one[m][kind][0])}–{_f(one[m][kind][1])}" for m in mats)
                     + " |")
    lines += ["", f"## Over {n} room{'s' if n != 1 else ''}", "",
              "Mean over rooms of each end of the min–max cell, with its 95 % bootstrap interval "
              f"({RESAMPLES} resamples of the rooms).", "", head, rule]
    agg = summary["aggregate"]

    def iv(s):
        return f"{_f(s['mean'])} [{_f(s['ci95'][0])}, {_f(s['ci95'][1])}]"

    lines.append("| Noise floor | " + " | ".join(iv(agg[m]["noise_floor"]) for m in mats) + " |")
    for kind in KINDS:
        lines.append(f"| {label[kind]} | " + " | ".join(f"{iv(agg[m][kind]['min'])} – {iv(agg[m][kind]['max'])}"
                                                        for m in mats) + " |")
    lines.append("| 2.5D light, its own noise (two seeds) | " + " | ".join(iv(agg[m]["mesh_noise"]) for m in mats)
                 + " |")
    lines += ["", "## Ratios", "", "Per room, the ratio of the errors averaged over the capture points; "
              "geometric mean over rooms [95 % bootstrap interval] (range), rooms where the ratio exceeds 1.", "",
              "| Ratio | " + " | ".join(MATERIAL_LABELS.get(m, m) for m in mats) + " |", rule]
    names = {"envmap_over_mesh": "Environment map / 2.5D light", "sphere_over_mesh": "Sphere proxy / 2.5D light",
             "mesh_over_noise": "2.5D light / noise floor"}
    for key, title in names.items():
        cells = []
        for m in mats:
            s = summary["ratios"][m][key]
            cells.append(f"{s['geomean']:.2f}× [{s['ci95'][0]:.2f}, {s['ci95'][1]:.2f}] "
                         f"({s['min']:.2f}–{s['max']:.2f}) {s['above_1']}/{s['n']}")
        lines.append(f"| {title} | " + " | ".join(cells) + " |")
    lines += ["", "## The paper's claim (2.5D light 2–5× below the environment map)", ""] + _verdict(summary)
    lines += ["", "## Per room", "", "| Room | " + " | ".join(f"env / 2.5D {m}" for m in mats) + " | lighting |",
              "|---|" + "---:|" * len(mats) + "---|"]
    for i, name in enumerate(summary["rooms"]):
        cells = [f"{summary['ratios'][m]['envmap_over_mesh']['per_room'][i]:.2f}" for m in mats]
        lines.append(f"| {name} | " + " | ".join(cells) + f" | {summary.get('lighting', {}).get(name, '')} |")
    if skipped:
        lines += ["", f"Skipped {len(skipped)} room(s) without room for the probes: " + ", ".join(sorted(skipped)) + "."]
    lines += ["", "Figures: `figures/probes-<material>.png` (probes × capture points, first room), "
              "`figures/motivation.png` (two objects relit from each capture point), `figures/ratios.png`."]
    return "\n".join(lines) + "\n"


def write_capacity_report(out, records: list[dict], cfg, skipped=None, wall_seconds=None,
                          resumed_rooms: int = 0) -> dict:
    """Write ``capacity.md``, ``capacity.json`` and the figures into ``out``; returns the summary."""
    from roomlight.evaluation.experiments.capacity_figures import write_capacity_figures
    from roomlight.evaluation.experiments.files import atomic_json, atomic_text

    out = Path(out)
    summary = summarize_capacity(records)
    summary["lighting"] = {r["name"]: f"{r['room'].get('room_type')}, {r['room'].get('lighting')}" for r in records}
    settings = cfg.to_dict()
    doc = {"settings": settings, "summary": summary, "rooms": records, "skipped": skipped or {},
           "wall_seconds": wall_seconds, "rooms_reused": resumed_rooms,
           "room_seconds": sum(r.get("seconds", 0.0) for r in records)}
    atomic_json(out / "capacity.json", doc)
    figures = write_capacity_figures(out, records, summary)
    text = capacity_markdown(summary, settings, wall_seconds, skipped, doc["room_seconds"], resumed_rooms)
    atomic_text(out / "capacity.md", text)
    summary["figures"] = [str(p) for p in figures]
    summary["markdown"] = text
    return summary

