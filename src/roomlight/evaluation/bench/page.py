"""``index.html`` of a benchmark report: what was run and how it is scored, the tables, the figures.

The page explains itself: the methods, the metrics, the settings of the run (``run.json``) and the
prior used, then the evaluation-view table (paper Table 2), the paired differences, the input-view
table, the fit times and one figure per scene with a caption.
"""

from __future__ import annotations

import html
import json
from pathlib import Path

import numpy as np

from roomlight.evaluation.harness.page import PAGE_STYLE, md_table_to_html

__all__ = ["write_index"]

def _run_settings(out: Path, records: list[dict]) -> dict:
    """``run.json`` of the results folder the report was made from (empty when not found)."""
    dirs = {Path(r["_dir"]) for r in records if r.get("_dir")}
    for d in sorted(dirs)[:1]:
        for parent in d.parents:
            f = parent / "run.json"
            if f.is_file():
                try:
                    return json.loads(f.read_text())
                except ValueError:
                    return {}
    return {}


def _method_text(name: str) -> str:
    """The registry's sentence about a method, for the report's reader."""
    from roomlight.fitting.methods import method_names
    from roomlight.fitting.methods import method as method_record

    return method_record(name).text if name in method_names() else "a method not described here"


def _about(records: list[dict], settings: dict) -> list[str]:
    from roomlight.evaluation.harness.metrics import LDR_GAMMA
    from roomlight.evaluation.harness.tables import METHOD_ORDER, kinds_by_method, ordered

    methods = ordered({r["method"] for r in records}, METHOD_ORDER)
    kinds = kinds_by_method(records)
    parts = ["<h2>What this report shows</h2>",
             ("<p>Each benchmark scene places objects in a room whose light is known (an HDR panorama with depth). "
              "Every method sees one image of the <em>input view</em> (two objects) and recovers the room's "
              "light from it; the recovered light then relights a held-out probe sphere in the <em>evaluation "
              "view</em>, which is compared with the ground-truth render of that view.</p>"),
             "<h3>Methods</h3><dl>"]
    for m in methods:
        parts.append(f"<dt>{html.escape(m)} ({html.escape(kinds.get(m, ''))})</dt>"
                     f"<dd>{html.escape(_method_text(m))}</dd>")
    parts += ["</dl><h3>Metrics</h3><dl>",
              f"<dt>PSNR LDR ↑</dt><dd>on the masked pixels after clipping to [0, 1] and gamma {LDR_GAMMA:g}, "
              "as an 8-bit recording would show them (dB, higher is better)</dd>",
              "<dt>RMSE HDR ↓</dt><dd>root mean square difference of linear radiance on the masked pixels</dd>",
              "<dt>RGB angular error ↓</dt><dd>mean angle between the two RGB vectors of each masked pixel "
              "(degrees): colour, not brightness</dd></dl>",
              "<p class='note'>Cells: mean ± standard deviation over scenes (population, ddof = 0); a cell with "
              "one scene shows its value alone. Best mean per column in bold (the oracle never counts).</p>",
              "<h3>Settings</h3><ul>"]
    fc = settings.get("fit_config") or {}
    if settings.get("bench"):
        parts.append(f"<li>benchmark: <code>{html.escape(str(settings['bench']))}</code></li>")
    if fc:
        parts.append(f"<li>fitting: {fc.get('iterations', '?')} iterations at {fc.get('spp', '?')} samples per "
                     f"pixel, learning rate {fc.get('lr', '?')}, direct maps at "
                     f"{'x'.join(str(v) for v in fc.get('direct_resolution') or ['?'])}, fitted on the "
                     f"{html.escape(str(fc.get('image', '?')))} image of the {html.escape(str(fc.get('view', '?')))} "
                     "view</li>")
    if settings.get("eval_spp"):
        parts.append(f"<li>scoring re-renders: {settings['eval_spp']} samples per pixel, "
                     f"path depth {settings.get('max_depth', '?')}</li>")
    prior = settings.get("model")
    if any(r["method"].startswith("prior") for r in records):
        parts.append(f"<li>prior: <code>{html.escape(str(prior))}</code></li>" if prior else
                     "<li>prior: not recorded in run.json</li>")
    parts.append("</ul>")
    return parts


def _timing_table(records: list[dict]) -> str:
    from roomlight.evaluation.harness.tables import METHOD_ORDER, ordered

    t: dict[str, list[float]] = {}
    for r in records:
        if r.get("fit_seconds") is not None:
            t.setdefault(r["method"], []).append(float(r["fit_seconds"]))
    if not t:
        return "<p class='note'>No fit times recorded.</p>"
    rows = "".join(f"<tr><td>{html.escape(m)}</td><td>{np.mean(t[m]):.1f}</td><td>{len(t[m])}</td></tr>"
                   for m in ordered(t, METHOD_ORDER))
    return f"<table><tr><th>Method</th><th>mean fit seconds</th><th>cases</th></tr>{rows}</table>"


def _caption(sid: str) -> str:
    from roomlight.evaluation.bench.figures import ERROR_RANGE

    return (f"Scene {html.escape(sid)}. Top row: the ground truth; below, one row per method with its "
            "evaluation-view scores (PSNR LDR, RMSE HDR, angular error). Columns: the held-out probe as "
            "recorded (gamma 2.2); the per-pixel mean absolute LDR difference to the ground truth on the probe, "
            f"one colour scale from 0 to {ERROR_RANGE:g} for every map (bar below); the input view the methods "
            "fitted; the emitter's radiance panorama; its radial depth on a log colour scale in metres, the same "
            "for every row (bar below; an env map has none, its light is at infinity).")


def write_index(out_dir, records: list[dict], figures: dict[str, Path], reference: str = "prior") -> Path:
    """``index.html``: the explanation, both tables (the paired one: ``reference`` against every other
    method), fit times, links to the files and every scene figure."""
    from roomlight.evaluation.harness.paired import paired_differences, paired_markdown, paired_title
    from roomlight.evaluation.harness.tables import MATERIAL_ORDER, markdown_table, ordered

    out = Path(out_dir)
    settings = _run_settings(out, records)
    parts = ["<!doctype html><html lang='en'><head><meta charset='utf-8'><title>roomlight benchmark</title>",
             f"<style>{PAGE_STYLE}</style></head><body>", "<h1>roomlight synthetic benchmark</h1>",
             (f"<p>{len(records)} cases, {len({r['scene'] for r in records})} scenes. Files: "
              "<a href='report.md'>report.md</a> · <a href='table.csv'>table.csv</a> · "
              "<a href='table_input.csv'>table_input.csv</a> · <a href='cases.csv'>cases.csv</a> · "
              "<a href='summary.json'>summary.json</a></p>"),
             *_about(records, settings),
             "<h2>Evaluation view (probe) — paper Table 2</h2>", md_table_to_html(markdown_table(records, "eval")),
             f"<h2>Paired differences: {html.escape(paired_title(reference))} (evaluation view)</h2>",
             md_table_to_html(paired_markdown(paired_differences(records, reference, "eval"), reference,
                                              ordered({r["material"] for r in records}, MATERIAL_ORDER))),
             "<h2>Input view (fitted objects)</h2>", md_table_to_html(markdown_table(records, "input")),
             "<h2>Fit time</h2>", _timing_table(records), "<h2>Scenes</h2>"]
    for sid, p in sorted(figures.items()):
        rel = Path(p).relative_to(out) if Path(p).is_relative_to(out) else Path(p)
        parts.append(f"<figure id='{html.escape(sid)}'><img src='{html.escape(str(rel))}' "
                     f"alt='figure of scene {html.escape(sid)}'><figcaption>{_caption(sid)}</figcaption></figure>")
    parts.append("<p class='note'>Generated by <code>roomlight bench report</code>.</p></body></html>")
    path = out / "index.html"
    path.write_text("\n".join(parts))
    return path
