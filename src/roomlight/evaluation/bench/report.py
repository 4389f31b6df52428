"""``roomlight bench report``: the paper's Table 2 from a results folder, as Markdown, CSV and JSON.

Layout (Table 2): one row per method (with its emitter representation), one column per
metric x material, each cell the mean +- standard deviation over the scenes of that material
(``np.std``, i.e. population std, ddof = 0). The evaluation view (the probe) is Table 2; the
input view (the fitted objects) is the supplementary "fitted view" table.

Files written to ``OUT`` (default ``RES/report``):

- ``report.md``     both tables, case counts, failed cases, mean fit time per method, and the
  cases whose recovered light leaves part of the probe outside it
- ``table.csv``     the evaluation-view table, wide: ``<metric>_<material>_{mean,std,n}``
- ``table_input.csv`` the same for the input view
- ``cases.csv``     one row per case and view with every metric (long format) and ``outside``,
  the share of the view's objects' surface the recovered emitter does not enclose (empty for an
  environment map)
- ``summary.json``  ``{"views": {view: {method: {material: {metric: {mean, std, n}}}}},
  "paired": {view: {baseline: {material: {metric: {mean, ci95, wins, n}}}}}, ...}`` (paired:
  per-scene differences prior - baseline, :mod:`roomlight.evaluation.harness.paired`; "outside": {view:
  [{case, share, psnr_ldr}]}, the cases with a share above 0)
- ``figures/*.png`` and ``index.html`` (see :mod:`roomlight.evaluation.bench.figures`)
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np

from roomlight.evaluation.harness.errors import BenchError
from roomlight.evaluation.harness.metrics import METRICS
from roomlight.evaluation.harness.paired import paired_differences, paired_markdown, paired_reference, paired_title
from roomlight.evaluation.harness.records import RUN_FILE, collect_failures, read_case_records
from roomlight.evaluation.harness.tables import (MATERIAL_ORDER, METHOD_ORDER, METRIC_LABELS, VIEWS, markdown_table, ordered,
                                    representation, summarize, write_wide_csv)

__all__ = ["collect_results", "collect_failures", "write_tables", "write_report",
           # re-exported from roomlight.evaluation.harness.tables, where the table layout lives
           "METRIC_LABELS", "METHOD_ORDER", "summarize", "representation", "markdown_table"]


def collect_results(res_dir) -> list[dict]:
    """Every case record under ``RES/cases`` (sorted by scene, then method), with its ``scene_path``."""
    bench = None
    run_file = Path(res_dir) / RUN_FILE
    if run_file.is_file():
        try:
            bench = json.loads(run_file.read_text()).get("bench")
        except ValueError:
            bench = None
    out = read_case_records(res_dir, ("scene", "method", "material", "metrics"), "roomlight bench run")
    for rec in out:
        if not rec.get("scene_path") and bench:
            rec["scene_path"] = str(Path(bench) / rec["scene"] / "scene.json")
    return out


def _cases_csv(path: Path, records: list[dict]) -> None:
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["scene", "panorama", "material", "method", "emitter_kind", "view", *METRICS, "pixels",
                    "fit_seconds", "best_iteration", "outside"])
        for r in records:
            for view in VIEWS:
                m = r["metrics"].get(view)
                if m:
                    w.writerow([r["scene"], r.get("panorama", ""), r["material"], r["method"],
                                r.get("emitter_kind", ""), view, *[m[k] for k in METRICS], m.get("pixels", ""),
                                r.get("fit_seconds", ""), r.get("best_iteration", ""),
                                (r.get("outside") or {}).get(view, "")])


def outside_cases(records: list[dict], view: str = "eval") -> list[dict]:
    """Cases whose recovered emitter leaves part of the view's objects outside it (results
    written before this was recorded have no ``outside`` and are not listed)."""
    rows = [{"case": f"{r['scene']}/{r['method']}", "share": float(r["outside"][view]),
             "psnr_ldr": float(r["metrics"][view]["psnr_ldr"])}
            for r in records if (r.get("outside") or {}).get(view, 0) > 0 and view in r["metrics"]]
    return sorted(rows, key=lambda x: -x["share"])


def _timing(records: list[dict]) -> dict[str, dict]:
    t: dict[str, list] = {}
    for r in records:
        if r.get("fit_seconds") is not None:
            t.setdefault(r["method"], []).append(float(r["fit_seconds"]))
    return {m: {"mean_fit_seconds": float(np.mean(v)), "cases": len(v)} for m, v in t.items()}


def write_tables(records: list[dict], out_dir, failures=None, reference: str | None = None) -> dict[str, Path]:
    """Write report.md, table.csv, table_input.csv, cases.csv and summary.json; return their paths.

    The paired tables hold ``reference - method`` per scene for every other method (see
    :func:`paired_reference`)."""
    reference = paired_reference(records, reference)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    failures = failures or []
    paths = {"csv": out / "table.csv", "csv_input": out / "table_input.csv", "cases": out / "cases.csv",
             "json": out / "summary.json", "markdown": out / "report.md"}
    write_wide_csv(paths["csv"], records, "eval")
    write_wide_csv(paths["csv_input"], records, "input")
    _cases_csv(paths["cases"], records)
    timing = _timing(records)
    summary = {"views": {v: summarize(records, v) for v in VIEWS}, "cases": len(records),
               "scenes": len({r["scene"] for r in records}),
               "methods": ordered({r["method"] for r in records}, METHOD_ORDER),
               "materials": ordered({r["material"] for r in records}, MATERIAL_ORDER),
               "timing": timing, "failed": [f.get("case", "?") for f in failures],
               "outside": {v: outside_cases(records, v) for v in VIEWS},
               "std": "population standard deviation over scenes (ddof = 0)",
               "paired_reference": reference,
               "paired": {v: paired_differences(records, reference, v) for v in VIEWS},
               "paired_note": (f"per-scene difference {reference} - baseline: mean, 95 % percentile-bootstrap "
                               f"interval of the mean, scenes won by {reference}")}
    paths["json"].write_text(json.dumps(summary, indent=2, allow_nan=True))
    md = ["# Benchmark results", "",
          f"{len(records)} cases, {summary['scenes']} scenes. Cells: mean ± std over scenes (one scene: its value "
          "alone); best in bold.", "",
          "## Evaluation view (probe sphere) — paper Table 2", "", markdown_table(records, "eval"),
          f"## Paired differences, evaluation view: {paired_title(reference)}", "",
          paired_markdown(summary["paired"]["eval"], reference, summary["materials"]),
          "## Input view (fitted objects) — supplementary fitted-view table", "", markdown_table(records, "input"),
          "## Paired differences, input view", "",
          paired_markdown(summary["paired"]["input"], reference, summary["materials"], note=False),
          "## Fit time", "", "| Method | mean fit seconds | cases |", "|---|---:|---:|"]
    for m in ordered(timing, METHOD_ORDER):
        md.append(f"| {m} | {timing[m]['mean_fit_seconds']:.1f} | {timing[m]['cases']} |")
    outside = summary["outside"]["eval"]
    if outside:
        md += ["", "## Probes outside the recovered light", "",
               "Cases whose recovered emitter does not enclose the whole evaluation probe (share of its "
               "surface outside): the probe is hidden behind the emitter and sees only its back faces, "
               "which emit nothing.", "", "| case | outside | PSNR LDR |", "|---|---:|---:|"]
        md += [f"| {o['case']} | {100 * o['share']:.0f} % | {o['psnr_ldr']:.2f} |" for o in outside]
    if failures:
        md += ["", "## Failed cases", ""]
        md += [f"- `{f.get('case', '?')}`: {f.get('type', '')}: {f.get('error', '')}" for f in failures]
    paths["markdown"].write_text("\n".join(md) + "\n")
    return paths


def write_report(res_dir, out_dir=None, figures: bool = True, progress: bool = True,
                 reference: str | None = None) -> dict[str, Path]:
    """Tables, per-scene figures and ``index.html`` of a results folder (see the module docstring);
    the paired tables compare ``reference`` (default: the prior) with every other method."""
    records = collect_results(res_dir)
    if not records:
        raise BenchError(f"{res_dir}: no finished case (no result.json under {Path(res_dir) / 'cases'})")
    failures = collect_failures(res_dir)
    out = Path(out_dir) if out_dir else Path(res_dir) / "report"
    paths = write_tables(records, out, failures, reference)
    figs: dict[str, Path] = {}
    if figures:
        from roomlight.evaluation.bench.figures import scene_figures

        figs = scene_figures(records, out / "figures", progress=progress)
    from roomlight.evaluation.bench.page import write_index

    paths["html"] = write_index(out, records, figs, paired_reference(records, reference))
    paths.update({f"figure:{k}": v for k, v in figs.items()})
    return paths
