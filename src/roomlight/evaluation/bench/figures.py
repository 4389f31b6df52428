"""Per-scene figures of a benchmark run and the ``index.html`` that gathers them.

One PNG per scene (paper Fig. 5 layout, one row per method below the ground truth):

==========  ===================================================================================
probe       the evaluation view cropped around the probe, gamma 2.2 (as the LDR metric sees it)
error       per-pixel mean |LDR difference| to the ground truth on the probe, 0 to 0.25 (inferno),
            one scale for every row, its colour bar below the figure
input       the input view (the fitted objects)
radiance    the emitter radiance panorama, gamma 2.2 at the camera exposure
depth       its radial depth, log colour map over the ground truth's range (env maps: none), with
            a colour bar in metres below the figure
==========  ===================================================================================
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from roomlight.core.color import to_display

__all__ = ["ERROR_RANGE", "scene_figure", "scene_figures"]

#: Upper end of the error maps' colour scale (mean absolute LDR difference).
ERROR_RANGE = 0.25


def _rgb_exr(path) -> np.ndarray:
    from roomlight.core.io import read_exr

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
    return f"PSNR {m['psnr_ldr']:.2f} dB   RMSE {m['rmse_hdr']:.3f}   angle {m['angular_error']:.2f}°"


def _colour_bars(fig, grid, row: int, error_cmap, vmin, vmax, log_depth: bool) -> None:
    """Horizontal colour bars under the error column (0 to ERROR_RANGE) and the depth column (metres)."""
    import matplotlib
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import LogNorm, Normalize

    bar = fig.colorbar(ScalarMappable(Normalize(0.0, ERROR_RANGE), error_cmap), cax=fig.add_subplot(grid[row, 1]),
                       orientation="horizontal")
    bar.set_ticks(np.linspace(0.0, ERROR_RANGE, 3))
    bar.set_label("mean |LDR difference|", fontsize=9)
    bar.ax.tick_params(labelsize=8)
    if vmin is None:
        return
    norm = LogNorm(vmin, vmax) if log_depth else Normalize(vmin, vmax)
    bar = fig.colorbar(ScalarMappable(norm, matplotlib.colormaps["turbo"]), cax=fig.add_subplot(grid[row, 4]),
                       orientation="horizontal")
    ticks = np.unique(np.round(np.geomspace(vmin, vmax, 5) if log_depth else np.linspace(vmin, vmax, 5), 1))
    bar.set_ticks(ticks, labels=[f"{t:g}" for t in ticks])
    bar.ax.minorticks_off()
    bar.set_label("radial depth (m)", fontsize=9)
    bar.ax.tick_params(labelsize=8)


def scene_figure(scene_path, records: list[dict], path) -> Path:
    """Write the figure of one scene (``records``: its results, one per method) to ``path``."""
    import matplotlib
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from roomlight.evaluation.harness.tables import representation
    from roomlight.core.io import colorize_depth, read_panorama
    from roomlight.fitting.scene.build import load_view_target
    from roomlight.fitting.scene.build import load_scene

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
            label = f"{rec['method']}\n({representation(str(rec.get('emitter_kind', '?')))})"
            rows.append((label, _rgb_exr(d / "eval.exr"), _rgb_exr(d / "input.exr"), pano,
                         _metrics_text(rec)))
        except Exception as exc:  # a half-written case must not stop the report
            warnings.warn(f"{d}: skipped in the figure ({exc})", stacklevel=2)
    cmap = matplotlib.colormaps["inferno"].with_extremes(bad=(0.25, 0.25, 0.25))
    fig = Figure(figsize=(13.0, 2.2 * len(rows) + 1.2), dpi=100)
    FigureCanvasAgg(fig)
    # one row per light, then a thin row for the colour bars shared by every row above
    grid = fig.add_gridspec(len(rows) + 1, 5, width_ratios=[1, 1, 1, 2, 2], height_ratios=[1] * len(rows) + [0.07],
                            wspace=0.06, hspace=0.45)
    titles = ["held-out probe\n(gamma 2.2)", "|LDR error|\non the probe", "input view\n(fitted objects)",
              "emitter radiance (gamma 2.2)", "emitter depth (m, log scale)"]
    gt_ldr = to_display(gt_eval)
    log_depth = vmin is not None and vmin > 0
    for r, (label, ev, inp, pano, text) in enumerate(rows):
        axes = [fig.add_subplot(grid[r, c]) for c in range(5)]
        for c, ax in enumerate(axes):
            ax.set_xticks([])
            ax.set_yticks([])
            if r == 0:
                ax.set_title(titles[c], fontsize=10)
        axes[0].imshow(to_display(ev)[crop])
        axes[0].set_ylabel(label, fontsize=10)
        if r == 0:
            axes[1].set_facecolor((0.25, 0.25, 0.25))
            axes[1].text(0.5, 0.5, "reference", ha="center", va="center", color="white", fontsize=9,
                         transform=axes[1].transAxes)
        else:
            err = np.abs(to_display(ev) - gt_ldr).mean(-1)
            err = np.ma.masked_where(~mask_eval, err)
            axes[1].imshow(err[crop], cmap=cmap, vmin=0.0, vmax=ERROR_RANGE)
            axes[0].set_xlabel(text, fontsize=9, loc="left")
        axes[2].imshow(to_display(inp))
        if pano is not None:
            axes[3].imshow(to_display(pano.radiance))
            if pano.depth is not None:
                axes[4].imshow(colorize_depth(pano.depth, vmin, vmax, log=log_depth))
            else:
                axes[4].set_facecolor((0.25, 0.25, 0.25))
                axes[4].text(0.5, 0.5, "env map: light at infinity", ha="center", va="center", color="white",
                             fontsize=9, transform=axes[4].transAxes)
    _colour_bars(fig, grid, len(rows), cmap, vmin, vmax, log_depth)
    fig.suptitle(f"{scene.metadata.get('benchmark', {}).get('panorama', '')} — "
                 f"{scene.metadata.get('benchmark', {}).get('material', '')}", fontsize=11)
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, bbox_inches="tight")
    return out


def scene_figures(records: list[dict], out_dir, progress: bool = True) -> dict[str, Path]:
    """One figure per scene of the results (see :func:`scene_figure`); returns {scene id: path}."""
    from roomlight.evaluation.harness.tables import METHOD_ORDER

    by_scene: dict[str, list[dict]] = {}
    for r in records:
        by_scene.setdefault(r["scene"], []).append(r)
    order = {m: i for i, m in enumerate(METHOD_ORDER)}
    items = sorted(by_scene.items())
    if progress:
        from roomlight.core.progress import progress_bar

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
