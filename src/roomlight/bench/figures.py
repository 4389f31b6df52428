"""Per-scene figures of a benchmark run and the ``index.html`` that gathers them.

One PNG per scene (paper Fig. 5 layout, one row per method below the ground truth):

==========  ===================================================================================
probe       the evaluation view cropped around the probe, gamma 2.2 (as the LDR metric sees it)
error       per-pixel mean |LDR difference| to the ground truth on the probe, 0 to 0.25 (inferno)
input       the input view (the fitted objects)
radiance    the emitter radiance panorama, gamma 2.2 at the camera exposure
depth       its radial depth, log colour map over the ground truth's range (env maps: none)
==========  ===================================================================================
"""

from __future__ import annotations

import html
import warnings
from pathlib import Path

import numpy as np

from roomlight.color import to_display

__all__ = ["ERROR_RANGE", "scene_figure", "scene_figures", "write_index"]

#: Upper end of the error maps' colour scale (mean absolute LDR difference).
ERROR_RANGE = 0.25


def _rgb_exr(path) -> np.ndarray:
    from roomlight.io import read_exr

    ch = read_exr(path)
    return np.stack([ch[c] for c in "RGB"], -1).astype(np.float32)


def _crop_box(mask: np.ndarray, pad: float = 0.15) -> tuple[slice, slice]:
    ys, xs = np.nonzero(mask)
    if ys.size == 0:
        return slice(None), slice(None)
    h, w = mask.shape
    cy, cx = 0.5 * (ys.min() + ys.max()), 0.5 * (xs.min() + xs.max())
    half = 0.5 * max(ys.max() - ys.min(), xs.max() - xs.min()) * (1 + 2 * pad) + 1
    y0, y1 = int(max(0, cy - half)), int(min(h, cy + half + 1))
    x0, x1 = int(max(0, cx - half)), int(min(w, cx + half + 1))
    return slice(y0, y1), slice(x0, x1)


def _metrics_text(rec: dict) -> str:
    m = rec["metrics"].get("eval", {})
    if not m:
        return ""
    return f"PSNR {m['psnr_ldr']:.2f}  RMSE {m['rmse_hdr']:.3f}  {m['angular_error']:.2f}°"


def scene_figure(scene_path, records: list[dict], path) -> Path:
    """Write the figure of one scene (``records``: its results, one per method) to ``path``."""
    import matplotlib
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from roomlight.io import colorize_depth, read_panorama
    from roomlight.scene.build import load_view_target
    from roomlight.scene.build import load_scene

    scene = load_scene(scene_path)
    gt_eval, mask_eval = (t.numpy() for t in load_view_target(scene.view("eval"), prefer="hdr"))
    gt_input, _ = load_view_target(scene.view("input"), prefer="hdr")
    gt_pano = scene.emitter.load() if scene.emitter else None
    crop = _crop_box(mask_eval)
    vmin = vmax = None
    if gt_pano is not None and gt_pano.depth is not None:
        vmin, vmax = float(gt_pano.depth.min()), float(gt_pano.depth.max())

    rows = [("ground truth", gt_eval, gt_input.numpy(), gt_pano, "")]
    for rec in records:
        d = Path(rec["_dir"])
        try:
            pano = read_panorama(d / "recovered.exr")
            rows.append((f"{rec['method']}", _rgb_exr(d / "eval.exr"), _rgb_exr(d / "input.exr"), pano,
                         _metrics_text(rec)))
        except Exception as exc:  # a half-written case must not stop the report
            warnings.warn(f"{d}: skipped in the figure ({exc})", stacklevel=2)
    cmap = matplotlib.colormaps["inferno"].with_extremes(bad=(0.25, 0.25, 0.25))
    fig = Figure(figsize=(13.0, 2.1 * len(rows) + 0.4), dpi=100)
    FigureCanvasAgg(fig)
    grid = fig.add_gridspec(len(rows), 5, width_ratios=[1, 1, 1, 2, 2], wspace=0.05, hspace=0.25)
    titles = ["probe (eval view)", "probe |LDR error|", "input view", "radiance", "depth"]
    gt_ldr = to_display(gt_eval)
    for r, (label, ev, inp, pano, text) in enumerate(rows):
        axes = [fig.add_subplot(grid[r, c]) for c in range(5)]
        for c, ax in enumerate(axes):
            ax.set_xticks([])
            ax.set_yticks([])
            if r == 0:
                ax.set_title(titles[c], fontsize=9)
        axes[0].imshow(to_display(ev)[crop])
        axes[0].set_ylabel(label, fontsize=9)
        if r == 0:
            axes[1].set_facecolor((0.25, 0.25, 0.25))
        else:
            err = np.abs(to_display(ev) - gt_ldr).mean(-1)
            err = np.ma.masked_where(~mask_eval, err)
            im = axes[1].imshow(err[crop], cmap=cmap, vmin=0.0, vmax=ERROR_RANGE)
            last_err = axes[1]
            axes[1].set_xlabel(text, fontsize=7)
        axes[2].imshow(to_display(inp))
        if pano is not None:
            axes[3].imshow(to_display(pano.radiance))
            if pano.depth is not None:
                axes[4].imshow(colorize_depth(pano.depth, vmin, vmax, log=vmin is not None and vmin > 0))
            else:
                axes[4].set_facecolor((0.25, 0.25, 0.25))
                axes[4].text(0.5, 0.5, "at infinity", ha="center", va="center", color="white", fontsize=9,
                             transform=axes[4].transAxes)
    if len(rows) > 1:
        fig.colorbar(im, ax=[last_err], fraction=0.05, pad=0.02).ax.tick_params(labelsize=6)
    fig.suptitle(f"{scene.metadata.get('benchmark', {}).get('panorama', '')} — "
                 f"{scene.metadata.get('benchmark', {}).get('material', '')}", fontsize=11)
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, bbox_inches="tight")
    return out


def scene_figures(records: list[dict], out_dir, progress: bool = True) -> dict[str, Path]:
    """One figure per scene of the results (see :func:`scene_figure`); returns {scene id: path}."""
    from roomlight.bench.tables import METHOD_ORDER

    by_scene: dict[str, list[dict]] = {}
    for r in records:
        by_scene.setdefault(r["scene"], []).append(r)
    order = {m: i for i, m in enumerate(METHOD_ORDER)}
    items = sorted(by_scene.items())
    if progress:
        from roomlight.progress import progress_bar

        items = progress_bar(items, desc="bench report", unit="figure")
    out = {}
    for sid, recs in items:
        recs = sorted(recs, key=lambda r: (order.get(r["method"], len(order)), r["method"]))
        scene_path = recs[0].get("scene_path")
        if not scene_path or not Path(scene_path).is_file():
            warnings.warn(f"scene {sid}: its scene file {scene_path} is gone; no figure", stacklevel=2)
            continue
        out[sid] = scene_figure(scene_path, recs, Path(out_dir) / (sid.replace("/", "_") + ".png"))
    return out


def _md_table_to_html(md: str) -> str:
    rows = [ln for ln in md.splitlines() if ln.startswith("|")]
    if len(rows) < 2:
        return f"<p>{html.escape(md)}</p>"
    out = ["<table>"]
    for i, ln in enumerate(rows):
        if i == 1:
            continue
        cells = [c.strip() for c in ln.strip("|").split("|")]
        tag = "th" if i == 0 else "td"
        out.append("<tr>" + "".join(
            f"<{tag}>" + (f"<b>{html.escape(c[2:-2])}</b>" if c.startswith("**") else html.escape(c)) + f"</{tag}>"
            for c in cells) + "</tr>")
    out.append("</table>")
    return "\n".join(out)


def write_index(out_dir, records: list[dict], figures: dict[str, Path]) -> Path:
    """``index.html``: both tables, links to the CSV/JSON/Markdown files and every scene figure."""
    from roomlight.bench.paired import paired_differences, paired_markdown
    from roomlight.bench.tables import MATERIAL_ORDER, markdown_table, ordered

    out = Path(out_dir)
    parts = ["<!doctype html><html><head><meta charset='utf-8'><title>roomlight benchmark</title>",
             ("<style>body{font-family:sans-serif;margin:2em;max-width:1400px}"
              "table{border-collapse:collapse;font-size:13px}td,th{border:1px solid #ccc;padding:3px 6px;"
              "text-align:center}img{max-width:100%}</style></head><body>"),
             "<h1>roomlight synthetic benchmark</h1>",
             ("<p>Files: <a href='report.md'>report.md</a> · <a href='table.csv'>table.csv</a> · "
              "<a href='table_input.csv'>table_input.csv</a> · <a href='cases.csv'>cases.csv</a> · "
              "<a href='summary.json'>summary.json</a></p>"),
             "<h2>Evaluation view (probe) — Table 2</h2>", _md_table_to_html(markdown_table(records, "eval")),
             "<h2>Paired differences: the prior against each baseline (evaluation view)</h2>",
             _md_table_to_html(paired_markdown(paired_differences(records, "prior", "eval"), "prior",
                                               ordered({r["material"] for r in records}, MATERIAL_ORDER))),
             ("<p>Cells: mean per-scene difference prior − baseline [95 % bootstrap interval of the mean] and "
              "the scenes the prior wins; ✓ interval entirely on the good side, ✗ entirely on the bad side.</p>"),
             "<h2>Input view (fitted objects)</h2>", _md_table_to_html(markdown_table(records, "input")),
             "<h2>Scenes</h2>"]
    for sid, p in sorted(figures.items()):
        rel = Path(p).relative_to(out) if Path(p).is_relative_to(out) else Path(p)
        parts.append(f"<h3 id='{html.escape(sid)}'>{html.escape(sid)}</h3><img src='{html.escape(str(rel))}' "
                     f"alt='{html.escape(sid)}'>")
    parts.append(f"<p><small>{len(records)} cases. Generated by <code>roomlight bench report</code>.</small></p>")
    parts.append("</body></html>")
    path = out / "index.html"
    path.write_text("\n".join(parts))
    return path
