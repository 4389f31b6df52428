"""Paired comparison of one method against the others, scene by scene, with bootstrap intervals.

A benchmark table of means hides how often a method wins and how sure we are that it does:
with ten scenes, one outlier moves a mean by a decibel. Every method is fitted to the same
scenes, so the right statistic is the per-scene *difference* ``method - baseline`` for each
material and metric, summarised by its mean, a 95 % percentile-bootstrap interval of that
mean (resampling scenes with replacement) and the number of scenes the method wins.

A difference is "better" when it has the metric's good sign: positive for PSNR, negative for
RMSE and angular error. An interval that excludes zero on the good side is a clear win.
"""

from __future__ import annotations

import math

import numpy as np

from roomlight.evaluation.harness.errors import BenchError
from roomlight.evaluation.harness.metrics import HIGHER_IS_BETTER, METRICS
from roomlight.core.stats import RESAMPLES, VERDICT_MARKS, bootstrap_mean_interval, interval_verdict

# bootstrap_mean_interval stays importable from here, where it was first defined.
__all__ = ["bootstrap_mean_interval", "mean_over_runs", "paired_differences", "paired_markdown", "paired_reference",
           "paired_title"]


def paired_reference(records: list[dict], reference: str | None) -> str:
    """The method a report's paired tables compare with the others: ``reference``, which must have
    finished cases among ``records``, or by default the prior (whose tables stay empty in results
    without it)."""
    if reference is None:
        return "prior"
    methods = sorted({r["method"] for r in records})
    if reference not in methods:
        raise BenchError(f"no finished case of the method {reference!r} to pair the others with; "
                         f"the results have {', '.join(methods)}")
    return reference


def paired_title(method: str) -> str:
    """What the paired tables of ``method`` compare, as the reports' headings say it."""
    return "the prior against each baseline" if method == "prior" else f"{method} against each other method"


def paired_differences(records: list[dict], method: str = "prior", view: str = "eval",
                       exclude=("oracle",), metrics=METRICS, higher_is_better=None, cluster=None) -> dict:
    """``{baseline: {material: {metric: stats}}}`` of ``method - baseline`` over shared scenes.

    ``records`` are benchmark results (``scene``, ``method``, ``material``, ``metrics[view]``).
    Scenes are paired by (scene, material); a scene where either side failed or has a
    non-finite value is left out of that comparison. ``stats`` holds ``mean``, ``ci95``
    (bootstrap interval of the mean difference), ``wins`` (scenes where ``method`` is strictly
    better), ``n`` and ``better`` ("higher" or "lower": which sign of the difference is good).
    ``metrics`` and ``higher_is_better`` (``{metric: bool}``) name other scores than the
    benchmark's three (e.g. material errors).

    ``cluster`` (a function of the scene name, e.g. the photo of ``"photo-00003/insert1"``) groups
    scenes that are not independent: their differences are averaged within each group first, and the
    mean, interval, wins and ``n`` are over the groups. Objects inserted into one photo share its fitted
    light, so resampling them one by one would treat two or three draws of one error as independent and
    give an interval narrower than the photos justify.
    """
    higher = HIGHER_IS_BETTER if higher_is_better is None else higher_is_better
    table: dict[tuple, dict] = {}
    for r in records:
        m = r.get("metrics", {}).get(view)
        if m is not None:
            table.setdefault((r["scene"], r["material"]), {})[r["method"]] = m
    baselines = sorted({meth for v in table.values() for meth in v} - {method} - set(exclude))
    out: dict = {}
    for base in baselines:
        for metric in metrics:
            per_material: dict[str, dict[str, list[float]]] = {}
            for (scene, material), by_method in sorted(table.items()):
                if method not in by_method or base not in by_method:
                    continue
                d = float(by_method[method][metric]) - float(by_method[base][metric])
                if math.isfinite(d):
                    group = scene if cluster is None else cluster(scene)
                    per_material.setdefault(material, {}).setdefault(group, []).append(d)
            for material, groups in per_material.items():
                a = np.asarray([np.mean(g) for g in groups.values()])
                good = a > 0 if higher[metric] else a < 0
                lo, hi = bootstrap_mean_interval(a)
                out.setdefault(base, {}).setdefault(material, {})[metric] = {
                    "mean": float(a.mean()), "ci95": [lo, hi], "wins": int(good.sum()), "n": int(a.size),
                    "better": "higher" if higher[metric] else "lower"}
    return out


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def mean_over_runs(runs: list[list[dict]]) -> list[dict]:
    """The records of repeated runs (the same scenes and methods, another seed each) as one run whose
    every score is the mean over the runs.

    A photo fit's own random numbers move one photo's score by up to 1.6 dB; pairing two methods on their
    means over K seeds compares what each gives on that scene rather than one draw of it.
    Records are matched by (scene, method, material); one missing from any run is left out, so every mean is
    over the same K runs. Within each view (``metrics[view]``), every number of the first run's record is
    averaged; one that another run lacks becomes nan (and :func:`paired_differences` leaves that scene out of
    that score), so no mean is over fewer runs than the others. Non-numbers are dropped; the other fields
    are the first run's. ``runs`` of one list return copies of its records.
    """
    if not runs:
        raise ValueError("mean_over_runs: no runs")

    def key(r):
        return r["scene"], r["method"], r["material"]

    keyed = [{key(r): r for r in run} for run in runs]
    out = []
    for k, first in keyed[0].items():
        group = [kr.get(k) for kr in keyed]
        if any(g is None for g in group):
            continue
        metrics = {}
        for view, scores in first.get("metrics", {}).items():
            views = [g.get("metrics", {}).get(view) or {} for g in group]
            metrics[view] = {name: float(np.mean([float(v[name]) for v in views]))
                             if all(_is_number(v.get(name)) for v in views) else math.nan
                             for name, value in scores.items() if _is_number(value)}
        out.append({**first, "metrics": metrics})
    return out


def _cell(s: dict, metric: str) -> str:
    digits = 2 if metric == "psnr_ldr" else 3
    lo, hi = s["ci95"]
    mark = VERDICT_MARKS[interval_verdict(lo, hi, s["n"], s["better"] == "higher")]
    return f"{s['mean']:+.{digits}f} [{lo:+.{digits}f}, {hi:+.{digits}f}] {s['wins']}/{s['n']}{mark}"


def paired_markdown(paired: dict, method: str = "prior", materials=None, labels: dict | None = None,
                    note: bool = True) -> str:
    """Markdown table: one row per baseline x metric, one column per material.

    Each cell: mean difference ``method - baseline`` [95 % bootstrap interval] wins/scenes;
    ✓ marks an interval entirely on the good side, ✗ entirely on the bad side. ``labels``
    (``{metric: row label}``) gives the rows for other metrics than the benchmark's three.
    ``note`` appends the line that explains the cells (once per page: False for later tables).
    """
    if not paired:
        return "_no paired scenes_\n"
    materials = materials or sorted({mat for b in paired.values() for mat in b})
    labels = labels or {"psnr_ldr": "Δ PSNR LDR (dB, ↑)", "rmse_hdr": "Δ RMSE HDR (↓)",
                        "angular_error": "Δ angular error (°, ↓)"}
    lines = [f"| {method} − baseline | metric | " + " | ".join(materials) + " |",
             "|---|---|" + "|".join([":---:"] * len(materials)) + "|"]
    for base, mats in paired.items():
        for metric in labels:
            cells = [_cell(mats[mat][metric], metric) if metric in mats.get(mat, {}) else "–" for mat in materials]
            lines.append(f"| {base} | {labels[metric]} | " + " | ".join(cells) + " |")
    if note:
        lines += ["", f"Cells: mean per-scene difference {method} − baseline [95 % bootstrap interval of the mean, "
                  f"{RESAMPLES} resamples] and the scenes {method} wins; ✓ interval entirely on the good side, "
                  "✗ entirely on the bad side."]
    return "\n".join(lines) + "\n"
