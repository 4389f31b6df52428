"""``roomlight bench report-photos``: the photo benchmark's tables, paired statistics, figures and page.

The probe scores take the synthetic benchmark's Table 2 layout (:mod:`roomlight.evaluation.harness.tables`):
one row per method, one column per metric x probe material, mean +- std over photos; and its
paired statistics (:mod:`roomlight.evaluation.harness.paired`): per photo, ``prior - baseline`` (or another
reference method's), with a 95 % bootstrap interval of the mean and the photos it wins. The
recovered materials get the same treatment (mean +- std of the per-photo mean error over objects,
and paired differences).

Files written to ``OUT`` (default ``RES/report``):

- ``report.md``     the tables, photo counts, failed cases, fit times
- ``table.csv``     the probe table, wide: ``<metric>_<material>_{mean,std,n}``
- ``materials.csv`` the material errors, one row per method
- ``cases.csv``     one row per photo, method and probe material (long format)
- ``summary.json``  everything above as JSON (``probes``, ``materials``, ``paired``, ``timing``)
- ``figures/<photo>.png`` and ``index.html``
"""

from __future__ import annotations

import csv
import html
import json
from pathlib import Path

import numpy as np

from roomlight.evaluation.harness.metrics import METRICS
from roomlight.evaluation.harness.page import PAGE_STYLE, md_table_to_html
from roomlight.evaluation.harness.paired import paired_differences, paired_markdown, paired_reference, paired_title
from roomlight.evaluation.harness.records import collect_failures, read_case_records
from roomlight.evaluation.harness.tables import markdown_table, ordered, summarize, write_wide_csv
from roomlight.errors import RoomlightError
from roomlight.fitting.methods import method_order
from roomlight.evaluation.photobench.objects import PROBE_MATERIALS
from roomlight.evaluation.photobench.runner import ORACLES, REFERENCES
from roomlight.evaluation.photobench.scoring import MATERIAL_METRICS

__all__ = ["collect_photo_results", "probe_records", "material_records", "materials_table", "write_photo_report",
           "PHOTO_METHOD_ORDER"]

#: Row order: the baselines, the prior, then the references (:mod:`roomlight.fitting.methods`).
PHOTO_METHOD_ORDER = method_order()
#: The steps from the oracle light down to the photo fit: (method, the reference it is compared with).
GAP_STEPS = (("prior-ceiling", "oracle", "the prior's capacity: its best latent for the whole room vs the room"),
             ("prior-samples", "prior-ceiling", "the fit from the paper's start vs the prior's ceiling"),
             ("prior-zero", "prior-ceiling", "the fit from z = 0 vs the prior's ceiling"),
             ("prior-view", "prior-ceiling", "the fit from the view encoder's start vs the prior's ceiling"),
             ("prior", "prior-ceiling", "the default fit vs the prior's ceiling"),
             ("prior-view", "prior-samples", "the view encoder's start vs the paper's start"),
             ("prior", "prior-samples", "the default start (the view encoder's, when the prior has one) vs the "
                                        "paper's start"))
MATERIAL_LABELS = {"albedo_rmse": "albedo RMSE ↓", "roughness_error": "roughness error ↓",
                   "metallic_error": "metallic error ↓"}
_EXCLUDE = REFERENCES
_LOWER = {m: False for m in MATERIAL_METRICS}


def collect_photo_results(res_dir) -> list[dict]:
    """Every case record under ``RES/cases`` (sorted by photo, then method)."""
    return read_case_records(res_dir, ("photo", "method", "probes"), "roomlight bench run-photos")


def probe_records(results: list[dict]) -> list[dict]:
    """One record per photo, method and probe material, in the synthetic benchmark's record shape
    (``scene``, ``material``, ``method``, ``metrics["eval"]``), so its tables and paired statistics apply."""
    out = []
    for r in results:
        for m, scores in r["probes"].items():
            out.append({"scene": r["photo"], "material": m, "method": r["method"],
                        "emitter_kind": r.get("emitter_kind", "?"), "fit_seconds": r.get("fit_seconds"),
                        "metrics": {"eval": {k: scores[k] for k in (*METRICS, "pixels") if k in scores}}})
    return out


def material_records(results: list[dict]) -> list[dict]:
    """One record per photo and fitted method: the mean material errors over the photo's objects."""
    return [{"scene": r["photo"], "material": "objects", "method": r["method"],
             "metrics": {"materials": r["materials"]["mean"]}}
            for r in results if r.get("materials") and r["materials"].get("per_object")]


def materials_table(records: list[dict]) -> str:
    """Markdown: one row per method, mean ± std over photos of each material error."""
    if not records:
        return "_no material estimates (oracles estimate none)_\n"
    by: dict[str, list[dict]] = {}
    for r in records:
        by.setdefault(r["method"], []).append(r["metrics"]["materials"])
    lines = ["| Method | " + " | ".join(MATERIAL_LABELS[k] for k in MATERIAL_METRICS) + " | photos |",
             "|---|" + ":---:|" * len(MATERIAL_METRICS) + "---:|"]
    for m in ordered(by, PHOTO_METHOD_ORDER):
        cells = []
        for k in MATERIAL_METRICS:
            a = np.asarray([v[k] for v in by[m]], np.float64)
            cells.append(f"{a.mean():.3f}" if a.size == 1 else f"{a.mean():.3f} ± {a.std():.3f}")
        lines.append(f"| {m} | " + " | ".join(cells) + f" | {len(by[m])} |")
    return "\n".join(lines) + "\n"


def outside_counts(results: list[dict]) -> dict:
    """Per method with a 2.5D light: how many probes have part of their surface outside the light
    (``{method: {"outside": n, "probes": m, "cases": [photo/probe, ...]}}``). Results written before the
    runner recorded ``probes_outside`` are measured from their ``recovered.exr``."""
    out: dict[str, dict] = {}
    for r in results:
        shares = r.get("probes_outside")
        if shares is None:
            shares = _outside_from_files(r)
        if not shares:
            continue
        entry = out.setdefault(r["method"], {"outside": 0, "probes": 0, "cases": []})
        for label, share in sorted(shares.items()):
            entry["probes"] += 1
            if share > 0:
                entry["outside"] += 1
                entry["cases"].append(f"{r['photo']}/probe {label} ({100 * share:.0f} %)")
    return out


def _outside_from_files(r: dict) -> dict:
    from roomlight.core.io import read_panorama
    from roomlight.evaluation.photobench.runner import REFERENCES
    from roomlight.core.light import Light
    from roomlight.evaluation.photobench.scoring import load_truth, probes_outside

    path = Path(r["_dir"]) / "recovered.exr"
    if r.get("emitter_kind") != "mesh" or not path.is_file():
        return {}
    pano = read_panorama(path)
    light = Light(pano.radiance, pano.depth, "mesh", pano.metadata["light_from_camera"])
    return probes_outside(load_truth(r["case_dir"]), light, given_depth=r["method"] not in REFERENCES)


def _timing(results: list[dict]) -> dict:
    t: dict[str, list[float]] = {}
    for r in results:
        if r["method"] not in ORACLES and r.get("fit_seconds") is not None:
            t.setdefault(r["method"], []).append(float(r["fit_seconds"]))
    return {m: {"mean_fit_seconds": float(np.mean(v)), "cases": len(v)} for m, v in t.items()}


def _cases_csv(path: Path, results: list[dict]) -> None:
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["photo", "method", "emitter_kind", "probe_material", *METRICS, "pixels", *MATERIAL_METRICS,
                    "fit_seconds"])
        for r in results:
            mat = (r.get("materials") or {}).get("mean") or {}
            for m, s in r["probes"].items():
                w.writerow([r["photo"], r["method"], r.get("emitter_kind", ""), m, *[s[k] for k in METRICS],
                            s.get("pixels", ""), *[mat.get(k, "") for k in MATERIAL_METRICS], r.get("fit_seconds", "")])


def _materials_csv(path: Path, records: list[dict]) -> None:
    by: dict[str, list[dict]] = {}
    for r in records:
        by.setdefault(r["method"], []).append(r["metrics"]["materials"])
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["method", *[f"{k}_{s}" for k in MATERIAL_METRICS for s in ("mean", "std")], "photos"])
        for m in ordered(by, PHOTO_METHOD_ORDER):
            row = [m]
            for k in MATERIAL_METRICS:
                a = np.asarray([v[k] for v in by[m]], np.float64)
                row += [float(a.mean()), float(a.std())]
            w.writerow(row + [len(by[m])])


def gap_steps(probes: list[dict]) -> list[dict]:
    """The paired differences of each step of :data:`GAP_STEPS` whose two methods were both run:
    ``[{"method", "reference", "what", "paired"}]`` (``paired`` as :func:`paired_differences` gives it)."""
    present = {r["method"] for r in probes}
    out = []
    for method, reference, what in GAP_STEPS:
        if method in present and reference in present:
            others = tuple(present - {method, reference})
            out.append({"method": method, "reference": reference, "what": what,
                        "paired": paired_differences(probes, method, "eval", exclude=others)})
    return out


def _gap_markdown(gap: list[dict], materials) -> list[str]:
    if not gap:
        return []
    md = ["## Where the gap is: each step from the oracle light to the photo fit", "",
          "Rows pair each photo's probes under two lights; the oracle is the room itself, the prior's ceiling "
          "its best approximation by the prior given the whole room.", ""]
    for step in gap:
        md += [f"**{step['method']} − {step['reference']}**: {step['what']}.", "",
               paired_markdown(step["paired"], step["method"], materials, note=False)]
    return md


def _outside_markdown(outside: dict) -> list[str]:
    if not outside:
        return []
    md = ["## Probes outside the 2.5D light", "",
          "A probe outside the light sees only the mesh's back faces, which emit nothing, and renders black.", "",
          "| Method | probes with part of their surface outside | which |", "|---|---:|---|"]
    for m in ordered(outside, PHOTO_METHOD_ORDER):
        e = outside[m]
        md.append(f"| {m} | {e['outside']} of {e['probes']} | {', '.join(e['cases']) or '–'} |")
    return md + [""]


def _markdown(results, probes, mats, paired, paired_mat, timing, failures, gap=(), outside=None, insertion=None,
              reference: str = "prior") -> str:
    photos = len({r["photo"] for r in results})
    md = ["# Photo benchmark results", "",
          f"{len(results)} cases, {photos} photos. Cells: mean ± std over photos (one photo: its value alone); "
          "best in bold (the oracles, references, never count).", "",
          "## Probes at the true positions under each recovered light", "", markdown_table(probes, "eval"),
          f"## Paired differences on the probes: {paired_title(reference)}", "",
          paired_markdown(paired, reference, [m for m in PROBE_MATERIALS if any(r["material"] == m for r in probes)]),
          *_gap_markdown(list(gap), [m for m in PROBE_MATERIALS if any(r["material"] == m for r in probes)]),
          *_outside_markdown(outside or {}),
          *_insertion_markdown(insertion, reference),
          "## Recovered materials (mean error over each photo's objects)", "", materials_table(mats),
          "## Paired differences on the materials", "",
          paired_markdown(paired_mat, reference, ["objects"], {k: f"Δ {v}" for k, v in MATERIAL_LABELS.items()},
                          note=False),
          "## Fit time", "", "| Method | mean fit seconds | cases |", "|---|---:|---:|"]
    for m in ordered(timing, PHOTO_METHOD_ORDER):
        md.append(f"| {m} | {timing[m]['mean_fit_seconds']:.1f} | {timing[m]['cases']} |")
    if failures:
        md += ["", "## Failed cases", ""]
        md += [f"- `{f.get('case', '?')}`: {f.get('type', '')}: {f.get('error', '')}" for f in failures]
    return "\n".join(md) + "\n"


def photo_figure(photo: str, results: list[dict], path: Path) -> Path:
    """One photo's figure: the ground truth, then one row per method: the photo or the recovered
    radiance panorama, and the probes in each material (the probe window, gamma 2.2)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from roomlight.core.color import to_display
    from roomlight.core.io import read_panorama
    from roomlight.evaluation.photobench import case as fmt

    case_dir = Path(results[0]["case_dir"])
    rows = [("ground truth", to_display(fmt.read_rgb_exr(case_dir / fmt.IMAGE)),
             {m: fmt.read_rgb_exr(case_dir / fmt.probe_image_name(m)) for m in PROBE_MATERIALS}, None)]
    for r in sorted(results, key=lambda r: ordered({x["method"] for x in results}, PHOTO_METHOD_ORDER).index(r["method"])):
        d = Path(r["_dir"])
        pano = to_display(read_panorama(d / "recovered.exr").radiance)
        imgs = {m: fmt.read_rgb_exr(d / f"probes_{m}.exr") for m in PROBE_MATERIALS if (d / f"probes_{m}.exr").is_file()}
        rows.append((f"{r['method']} ({r.get('emitter_kind', '?')})", pano, imgs, r["probes"]))
    fig, axes = plt.subplots(len(rows), 1 + len(PROBE_MATERIALS), figsize=(3.2 * (1 + len(PROBE_MATERIALS)),
                                                                            2.4 * len(rows)), squeeze=False)
    for i, (name, left, imgs, scores) in enumerate(rows):
        axes[i, 0].imshow(left)
        axes[i, 0].set_title(name if i else f"{photo}: the photo", fontsize=9)
        for j, m in enumerate(PROBE_MATERIALS, start=1):
            ax = axes[i, j]
            if m in imgs:
                ax.imshow(to_display(imgs[m]), interpolation="nearest")
            title = m if scores is None else (f"{m}: {scores[m]['psnr_ldr']:.1f} dB, {scores[m]['angular_error']:.1f}°"
                                              if m in scores else m)
            ax.set_title(title, fontsize=8)
        for ax in axes[i]:
            ax.set_xticks([])
            ax.set_yticks([])
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.stem}.partial.png")
    fig.savefig(tmp, dpi=90)
    plt.close(fig)
    tmp.replace(path)
    return path


def _index(out: Path, results, probes, mats, paired, paired_mat, timing, figures: dict, settings: dict,
           reference: str = "prior") -> Path:

    methods = ordered({r["method"] for r in results}, PHOTO_METHOD_ORDER)
    parts = ["<!doctype html><html lang='en'><head><meta charset='utf-8'><title>roomlight photo benchmark</title>",
             f"<style>{PAGE_STYLE}</style></head><body>", "<h1>roomlight photo benchmark</h1>",
             (f"<p>{len(results)} cases, {len({r['photo'] for r in results})} photos, methods: "
              f"{html.escape(', '.join(methods))}. Files: <a href='report.md'>report.md</a> · "
              "<a href='table.csv'>table.csv</a> · <a href='materials.csv'>materials.csv</a> · "
              "<a href='cases.csv'>cases.csv</a> · <a href='summary.json'>summary.json</a></p>"),
             "<h2>What this report shows</h2>",
             ("<p>Each photo is a path-traced view of a procedural room with two or three inserted objects of known "
              "principled materials. Every method fits the room's light (and the objects' materials) from the photo, "
              "its depth and its object mask. Probe spheres (gray diffuse, silver matte, silver mirror) are then "
              "rendered at several true positions near the objects under the recovered light and compared with the "
              "same probes path-traced in the real room: the ground truth is full light transport, not an emitter. "
              "<em>oracle</em> is the room captured as a 2.5D light at the probes; <em>oracle-envmap</em> the same "
              "radiance at infinity: the best each representation can do.</p>"),
             f"<p class='note'>Scoring renders: {settings.get('eval_spp', '?')} samples per pixel, path depth "
             f"{settings.get('max_depth', '?')}; fit preset {html.escape(str(settings.get('preset', '?')))}; prior "
             f"{html.escape(str(settings.get('model', 'not recorded')))}.</p>",
             "<h2>Probes</h2>", md_table_to_html(markdown_table(probes, "eval")),
             f"<h2>Paired differences on the probes: {html.escape(paired_title(reference))}</h2>",
             md_table_to_html(paired_markdown(paired, reference, list(PROBE_MATERIALS))),
             "<h2>Recovered materials</h2>", md_table_to_html(materials_table(mats)),
             "<h2>Paired differences on the materials</h2>",
             md_table_to_html(paired_markdown(paired_mat, reference, ["objects"],
                                              {k: f"Δ {v}" for k, v in MATERIAL_LABELS.items()}, note=False)),
             "<h2>Fit time</h2>"]
    rows = "".join(f"<tr><td>{html.escape(m)}</td><td>{timing[m]['mean_fit_seconds']:.1f}</td>"
                   f"<td>{timing[m]['cases']}</td></tr>" for m in ordered(timing, PHOTO_METHOD_ORDER))
    parts.append(f"<table><tr><th>Method</th><th>mean fit seconds</th><th>cases</th></tr>{rows}</table>"
                 if rows else "<p class='note'>No fit times (oracles only).</p>")
    parts.append("<h2>Photos</h2>")
    for photo, p in sorted(figures.items()):
        rel = Path(p).relative_to(out)
        parts.append(f"<figure id='{html.escape(photo)}'><img src='{html.escape(str(rel))}' alt='probes of "
                     f"{html.escape(photo)}'><figcaption>{html.escape(photo)}: top row the photo and the true probes "
                     "(cropped around them); below, per method, its recovered radiance panorama and the probes under "
                     "its light, with PSNR LDR and RGB angular error per material.</figcaption></figure>")
    parts.append("<p class='note'>Generated by <code>roomlight bench report-photos</code>.</p></body></html>")
    path = out / "index.html"
    path.write_text("\n".join(parts))
    return path


#: Scores of an inserted object (photobench.insertion) and whether higher is better.
#: (``shadow_psnr_ldr``: the region without the object; records made before it was scored lack it, and their
#: reports keep their columns.)
INSERT_METRICS = {"psnr_ldr": True, "ssim": True, "object_psnr_ldr": True, "shadow_psnr_ldr": True, "rmse_hdr": False}
INSERT_LABELS = {"psnr_ldr": "region PSNR LDR ↑", "ssim": "region SSIM ↑", "object_psnr_ldr": "object PSNR LDR ↑",
                 "shadow_psnr_ldr": "shadow PSNR LDR ↑", "rmse_hdr": "region RMSE HDR ↓"}


def insertion_records(results: list[dict]) -> list[dict]:
    """One record per photo, inserted object and method, in the benchmark's record shape (scene = photo/object)."""
    out = []
    for r in results:
        for e in r.get("insertion") or []:
            if e.get("visible"):
                out.append({"scene": f"{r['photo']}/{e['id']}", "material": "objects", "method": r["method"],
                            "distance_m": e["distance_m"],
                            "metrics": {"insert": {k: e[k] for k in INSERT_METRICS if k in e}}})
    return out


def insertion_photo(scene: str) -> str:
    """The photo of an :func:`insertion_records` scene ("photo-00003/insert1" -> "photo-00003"): the group
    whose objects share one fitted light, which paired statistics resample as one draw."""
    return scene.split("/", 1)[0]


def insert_metrics(records: list[dict]) -> dict[str, bool]:
    """The insertion scores every record has, in :data:`INSERT_METRICS` order."""
    have = set(INSERT_METRICS)
    for r in records:
        have &= set(r["metrics"]["insert"])
    return {k: v for k, v in INSERT_METRICS.items() if k in have}


def paired_insertion(records: list[dict], method: str) -> tuple[dict, dict]:
    """``method`` against every other method on the inserted objects' scores (:func:`insertion_records`),
    as :func:`~roomlight.evaluation.harness.paired.paired_differences` gives them: paired per object, and per
    photo (:func:`insertion_photo`: each photo's object differences averaged before resampling)."""
    metrics = insert_metrics(records)
    kw = dict(exclude=(), metrics=tuple(metrics), higher_is_better=metrics)
    return (paired_differences(records, method, "insert", **kw),
            paired_differences(records, method, "insert", cluster=insertion_photo, **kw))


def insertion_summary(records: list[dict], reference: str = "prior") -> dict:
    """Means per method, paired differences of ``reference`` against the others, and whether the 2.5D
    light's advantage over the prior at infinity grows with the object's distance from the camera."""
    from roomlight.core.stats import bootstrap_mean_interval, bootstrap_slope_interval

    by: dict[str, dict[str, list[float]]] = {}
    for r in records:
        for k, v in r["metrics"]["insert"].items():
            by.setdefault(r["method"], {}).setdefault(k, []).append(float(v))
    methods = {m: {k: {"mean": float(np.nanmean(v)), "std": float(np.nanstd(v)), "n": len(v)} for k, v in d.items()}
               for m, d in by.items()}
    metrics = insert_metrics(records)
    paired, paired_by_photo = paired_insertion(records, reference)
    # distance: per object, prior - prior-envmap region PSNR against the distance
    table: dict[str, dict] = {}
    for r in records:
        table.setdefault(r["scene"], {"d": r["distance_m"]})[r["method"]] = r["metrics"]["insert"]["psnr_ldr"]
    both = [(scene, v) for scene, v in table.items() if "prior" in v and "prior-envmap" in v]
    pairs = [(v["d"], v["prior"] - v["prior-envmap"]) for _, v in both]
    distance = None
    if len(pairs) >= 4:
        d, diff = np.asarray(pairs).T
        med = float(np.median(d))
        near, far = diff[d <= med], diff[d > med]
        slope, lo, hi = bootstrap_slope_interval(d, diff)
        # a photo's objects share its fitted light: resampling photos is the interval of independent draws
        _, plo, phi = bootstrap_slope_interval(d, diff, clusters=[insertion_photo(scene) for scene, _ in both])
        distance = {"n": len(pairs), "median_m": med, "slope_db_per_m": slope, "slope_ci95": [lo, hi],
                    "slope_ci95_by_photo": [plo, phi],
                    "near": {"mean": float(near.mean()), "ci95": list(bootstrap_mean_interval(near)), "n": len(near)},
                    "far": {"mean": float(far.mean()), "ci95": list(bootstrap_mean_interval(far)), "n": len(far)}}
    return {"methods": methods, "paired": paired, "paired_by_photo": paired_by_photo, "distance": distance,
            "metrics": list(metrics)}


def insertion_truths(results: list[dict]) -> str:
    """In words, the truth the records' inserted objects were scored against (a mix is said as such)."""
    seen = {json.dumps(r.get("insertion_truth") or {"image": "insert.exr", "spp": None}, sort_keys=True)
            for r in results if r.get("insertion")}
    if not seen:
        return ""
    if len(seen) > 1:
        return ("a mix of truths (records made before and after their photos got a clean insertion truth): "
                "run run-photos again on these results to score every record against the same one")
    stamp = json.loads(seen.pop())
    if stamp.get("spp"):
        return f"the scene path-traced again at {stamp['spp']} samples per pixel with a seed of its own ({stamp['image']})"
    return ("the scene rendered with the photo's own samples and seed (insert.exr), as noisy as a composite: "
            "rebuild the photos with make-photos --insert-spp for a clean truth")


def _insertion_markdown(summary: dict | None, reference: str = "prior") -> list[str]:
    if not summary or not summary["methods"]:
        return []
    labels = {k: INSERT_LABELS[k] for k in summary.get("metrics", INSERT_LABELS)}
    truth = f" Truth: {summary['truth']}." if summary.get("truth") else ""
    md = ["## Inserted objects (roomlight insert)", "",
          "Each photo's new objects composited under each recovered light by differential rendering (`naive-paste`: "
          "lit by a uniform light of the photo's mean colour, alone) against their path-traced truth in the room; "
          "the region is the object dilated by its projected radius, covering its shadow. Mean ± std over objects."
          + truth, "",
          "| Method | " + " | ".join(labels.values()) + " | objects |",
          "|---|" + ":---:|" * len(labels) + "---:|"]
    for m in ordered(summary["methods"], PHOTO_METHOD_ORDER):
        cells = [f"{summary['methods'][m][k]['mean']:.3f} ± {summary['methods'][m][k]['std']:.3f}" if k in ("ssim", "rmse_hdr")
                 else f"{summary['methods'][m][k]['mean']:.2f} ± {summary['methods'][m][k]['std']:.2f}" for k in labels]
        md.append(f"| {m} | " + " | ".join(cells) + f" | {summary['methods'][m]['psnr_ldr']['n']} |")
    row_labels = {k: f"Δ {v}" for k, v in labels.items()}
    md += [""] + (["Paired per object:", ""] if summary["paired"] else []) + [
        paired_markdown(summary["paired"], reference, ["objects"], row_labels, note=False)]
    if summary.get("paired_by_photo"):
        md += ["", "Paired per photo (its objects' differences averaged: a photo's objects share its fitted light, so "
               "only this interval resamples independent draws):", "",
               paired_markdown(summary["paired_by_photo"], reference, ["objects"], row_labels, note=False)]
    d = summary.get("distance")
    if d:
        md += [f"**Does the 2.5D light's advantage grow with distance?** prior − prior-envmap region PSNR per object "
               f"({d['n']} objects): nearer than the median {d['median_m']:.2f} m {d['near']['mean']:+.2f} dB "
               f"[{d['near']['ci95'][0]:+.2f}, {d['near']['ci95'][1]:+.2f}], farther {d['far']['mean']:+.2f} dB "
               f"[{d['far']['ci95'][0]:+.2f}, {d['far']['ci95'][1]:+.2f}]; slope {d['slope_db_per_m']:+.2f} dB/m "
               f"[{d['slope_ci95'][0]:+.2f}, {d['slope_ci95'][1]:+.2f}] (bootstrap over objects)"
               f", [{d['slope_ci95_by_photo'][0]:+.2f}, {d['slope_ci95_by_photo'][1]:+.2f}] over photos.", ""]
    return md


def write_photo_report(res_dir, out_dir=None, figures: bool = True, progress: bool = True,
                       reference: str | None = None) -> dict[str, Path]:
    """Write the report of a results folder (module docstring); returns the files by role. The paired
    tables compare ``reference`` (default: the prior) with every other method; the gap steps and the
    distance analysis are the prior's own."""
    results = collect_photo_results(res_dir)
    if not results:
        raise RoomlightError(f"{res_dir}: no finished case (no result.json under {Path(res_dir) / 'cases'})")
    failures = collect_failures(res_dir)
    out = Path(out_dir) if out_dir else Path(res_dir) / "report"
    out.mkdir(parents=True, exist_ok=True)
    settings = {}
    run_file = Path(res_dir) / "run.json"
    if run_file.is_file():
        try:
            settings = json.loads(run_file.read_text())
        except ValueError:
            settings = {}
    probes = probe_records(results)
    mats = material_records(results)
    reference = paired_reference(results, reference)
    paired = paired_differences(probes, reference, "eval", exclude=_EXCLUDE)
    paired_mat = paired_differences(mats, reference, "materials", exclude=_EXCLUDE, metrics=MATERIAL_METRICS,
                                    higher_is_better=_LOWER)
    gap = gap_steps(probes)
    outside = outside_counts(results)
    timing = _timing(results)
    inserted = insertion_records(results)
    ins_summary = {**insertion_summary(inserted, reference), "truth": insertion_truths(results)} if inserted else None
    paths = {"markdown": out / "report.md", "csv": out / "table.csv", "materials": out / "materials.csv",
             "cases": out / "cases.csv", "json": out / "summary.json"}
    write_wide_csv(paths["csv"], probes, "eval")
    _materials_csv(paths["materials"], mats)
    _cases_csv(paths["cases"], results)
    mat_summary: dict = {}
    for r in mats:
        mat_summary.setdefault(r["method"], []).append(r["metrics"]["materials"])
    summary = {"cases": len(results), "photos": len({r["photo"] for r in results}),
               "methods": ordered({r["method"] for r in results}, PHOTO_METHOD_ORDER),
               "probes": summarize(probes, "eval"),
               "materials": {m: {k: {"mean": float(np.mean([v[k] for v in vals])),
                                     "std": float(np.std([v[k] for v in vals])), "n": len(vals)}
                                 for k in MATERIAL_METRICS} for m, vals in mat_summary.items()},
               "paired_reference": reference,
               "paired": {"probes": paired, "materials": paired_mat}, "gap_steps": gap, "probes_outside": outside, "timing": timing,
               "insertion": ins_summary,
               "failed": [f.get("case", "?") for f in failures], "settings": settings,
               "std": "population standard deviation over photos (ddof = 0)"}
    paths["json"].write_text(json.dumps(summary, indent=2, allow_nan=True))
    paths["markdown"].write_text(_markdown(results, probes, mats, paired, paired_mat, timing, failures, gap, outside,
                                           ins_summary, reference))
    figs: dict[str, Path] = {}
    if figures:
        by: dict[str, list[dict]] = {}
        for r in results:
            by.setdefault(r["photo"], []).append(r)
        items = sorted(by.items())
        bar = None
        if progress:
            from roomlight.core.progress import progress_bar

            bar = progress_bar(total=len(items), desc="report-photos", unit="figure")
        for photo, rs in items:
            figs[photo] = photo_figure(photo, rs, out / "figures" / f"{photo}.png")
            if bar is not None:
                bar.update()
        if bar is not None:
            bar.close()
    paths["html"] = _index(out, results, probes, mats, paired, paired_mat, timing, figs, settings, reference)
    paths.update({f"figure:{k}": v for k, v in figs.items()})
    return paths
