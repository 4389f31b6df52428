"""The benchmark's tables: Table 2's layout (rows, columns, bold best) as Markdown and CSV.

One row per method (with its emitter representation), one column per metric x material, each
cell the mean +- standard deviation over the scenes of that material (``np.std``, population
std, ddof = 0). :mod:`roomlight.evaluation.bench.report` writes them to files; :mod:`roomlight.evaluation.bench.figures`
puts them into ``index.html``.
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np

from roomlight.evaluation.harness.metrics import HIGHER_IS_BETTER, METRICS
from roomlight.fitting.methods import is_reference, method_order

__all__ = ["METRIC_LABELS", "METHOD_ORDER", "MATERIAL_ORDER", "VIEWS", "ordered", "representation", "summarize",
           "kinds_by_method", "markdown_table", "write_wide_csv"]

METRIC_LABELS = {"psnr_ldr": "PSNR LDR ↑", "rmse_hdr": "RMSE HDR ↓", "angular_error": "RGB angular error (°) ↓"}
#: Row order of every table (the paper's: smoothness baselines, then the priors, then the references;
#: :mod:`roomlight.fitting.methods`); names not in it follow.
METHOD_ORDER = method_order()
MATERIAL_ORDER = ("diffuse", "matte", "mirror")
VIEWS = ("eval", "input")


def ordered(values, order) -> list[str]:
    """``values`` without repeats, those in ``order`` first (in that order), the rest sorted."""
    vals = sorted(set(values))
    return [v for v in order if v in vals] + [v for v in vals if v not in order]


def representation(kind: str) -> str:
    """Display name of an emitter kind (``mesh``, ``envmap``, ``sphere:R``)."""
    if kind.startswith("sphere"):
        return "Sphere proxy"
    return {"mesh": "2.5D AL", "envmap": "Env map"}.get(kind, kind)


def summarize(records: list[dict], view: str = "eval") -> dict:
    """``{method: {material: {metric: {"mean", "std", "n"}}}}`` over the records of one view."""
    groups: dict = {}
    for r in records:
        m = r["metrics"].get(view)
        if m is None:
            continue
        g = groups.setdefault(r["method"], {}).setdefault(r["material"], {k: [] for k in METRICS})
        for k in METRICS:
            g[k].append(float(m[k]))
    out: dict = {}
    for method, mats in groups.items():
        for mat, vals in mats.items():
            for k, v in vals.items():
                a = np.asarray(v, np.float64)
                out.setdefault(method, {}).setdefault(mat, {})[k] = {
                    "mean": float(a.mean()), "std": float(a.std()) if np.isfinite(a).all() else float("nan"),
                    "n": int(a.size)}
    return out


def _fmt(x: float, metric: str) -> str:
    if math.isinf(x):
        return "inf"
    if math.isnan(x):
        return "nan"
    return f"{x:.2f}" if metric == "psnr_ldr" else f"{x:.3f}"


def _best(summary: dict, methods, material: str, metric: str) -> str | None:
    vals = [(summary[m][material][metric]["mean"], m) for m in methods
            if not is_reference(m) and material in summary.get(m, {})]  # a reference is never the best
    vals = [(v, m) for v, m in vals if not math.isnan(v)]
    if len(vals) < 2:
        return None
    return (max if HIGHER_IS_BETTER[metric] else min)(vals)[1]


def kinds_by_method(records) -> dict[str, str]:
    """``{method: emitter representation(s)}``, e.g. ``{"prior": "2.5D AL"}``."""
    kinds: dict[str, set] = {}
    for r in records:
        kinds.setdefault(r["method"], set()).add(representation(r.get("emitter_kind", "?")))
    return {m: "/".join(sorted(k)) for m, k in kinds.items()}


def markdown_table(records: list[dict], view: str = "eval") -> str:
    """The Table 2 layout as Markdown (best mean per column in bold; an oracle never counts)."""
    summary = summarize(records, view)
    if not summary:
        return "_no results for this view_\n"
    methods = ordered(summary, METHOD_ORDER)
    materials = ordered([mat for m in summary.values() for mat in m], MATERIAL_ORDER)
    kinds = kinds_by_method(records)
    head = ["Method", "Emitter"] + [f"{METRIC_LABELS[k]} {mat}" for k in METRICS for mat in materials]
    lines = ["| " + " | ".join(head) + " |", "|" + "|".join(["---"] * 2 + [":---:"] * (len(head) - 2)) + "|"]
    best = {(k, mat): _best(summary, methods, mat, k) for k in METRICS for mat in materials}
    for m in methods:
        cells = [m, kinds.get(m, "")]
        for k in METRICS:
            for mat in materials:
                s = summary[m].get(mat, {}).get(k)
                if s is None:
                    cells.append("–")
                    continue
                # one scene has no spread to show
                text = _fmt(s["mean"], k) if s["n"] == 1 else f"{_fmt(s['mean'], k)} ± {_fmt(s['std'], k)}"
                cells.append(f"**{text}**" if best[(k, mat)] == m else text)
        lines.append("| " + " | ".join(cells) + " |")
    n = {mat: max(summary[m].get(mat, {}).get(METRICS[0], {}).get("n", 0) for m in methods) for mat in materials}
    lines.append("")
    lines.append("Scenes per material: " + ", ".join(f"{mat} {n[mat]}" for mat in materials) + ".")
    return "\n".join(lines) + "\n"


def write_wide_csv(path: Path, records: list[dict], view: str) -> None:
    """One view's table as CSV: a row per method, ``<metric>_<material>_{mean,std,n}`` columns."""
    summary = summarize(records, view)
    methods = ordered(summary, METHOD_ORDER)
    materials = ordered([mat for m in summary.values() for mat in m], MATERIAL_ORDER)
    kinds = kinds_by_method(records)
    cols = [f"{k}_{mat}_{s}" for k in METRICS for mat in materials for s in ("mean", "std", "n")]
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["method", "emitter"] + cols)
        for m in methods:
            row = [m, kinds.get(m, "")]
            for k in METRICS:
                for mat in materials:
                    s = summary[m].get(mat, {}).get(k)
                    row += [s["mean"], s["std"], s["n"]] if s else ["", "", 0]
            w.writerow(row)
