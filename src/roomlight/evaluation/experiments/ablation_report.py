"""The ablation table (``OUT/ablation.md``, ``ablation.json``) and its figures.

The table has the paper's layout: latent fitting (PSNR, SSIM, LPIPS on LDR; PSNR on HDR; depth
AbsRel) and matte inverse rendering (PSNR LDR, RMSE HDR, RGB angular error of the evaluation
probe), the best value of each column in bold. Below it, each row's difference to the full model,
paired by panorama (latent fits) or scene (inverse rendering), with a 95 % percentile-bootstrap
interval of the mean difference (:func:`roomlight.core.stats.bootstrap_mean_interval`).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from roomlight.core.stats import RESAMPLES, bootstrap_mean_interval
from roomlight.evaluation.experiments.ablation_rows import ROW_LABELS

__all__ = ["COLUMNS", "ablation_markdown", "paired_to_full", "write_ablation_report"]

#: (section, key, title, higher is better).
COLUMNS = [
    ("latent", "psnr_ldr", "PSNR LDR ↑", True),
    ("latent", "ssim_ldr", "SSIM LDR ↑", True),
    ("latent", "lpips_ldr", "LPIPS LDR ↓", False),
    ("latent", "psnr_hdr", "PSNR HDR ↑", True),
    ("latent", "abs_rel", "AbsRel depth ↓", False),
    ("matte", "psnr_ldr", "PSNR LDR ↑", True),
    ("matte", "rmse_hdr", "RMSE HDR ↓", False),
    ("matte", "angular_error", "Angular error (°) ↓", False),
]


def _value(rec: dict, section: str, key: str) -> float:
    v = rec.get(section, {}).get(key)
    return float("nan") if v is None else float(v)


def _fmt(v: float, key: str) -> str:
    if not math.isfinite(v):
        return "–"
    return f"{v:.3f}" if key in ("ssim_ldr", "lpips_ldr", "abs_rel", "rmse_hdr") else f"{v:.2f}"


def paired_to_full(rows: dict) -> dict:
    """``{row: {section/key: {mean, ci95, wins, n}}}``: per-panorama / per-scene difference row − full."""
    if "full" not in rows:
        return {}
    full = rows["full"]
    out: dict = {}
    for row, rec in rows.items():
        if row == "full":
            continue
        for section, key, _title, higher in COLUMNS:
            if section == "latent":
                a = {p["name"]: p.get(key) for p in full.get("latent_per_image", [])}
                b = {p["name"]: p.get(key) for p in rec.get("latent_per_image", [])}
            else:
                a = {s: m.get(key) for s, m in full.get("matte_per_scene", {}).items()}
                b = {s: m.get(key) for s, m in rec.get("matte_per_scene", {}).items()}
            diffs = [b[n] - a[n] for n in a if n in b and a[n] is not None and b[n] is not None
                     and math.isfinite(a[n]) and math.isfinite(b[n])]
            if not diffs:
                continue
            d = np.asarray(diffs)
            lo, hi = bootstrap_mean_interval(d)
            out.setdefault(row, {})[f"{section}/{key}"] = {
                "mean": float(d.mean()), "ci95": [lo, hi], "n": int(d.size),
                "better": int(((d > 0) if higher else (d < 0)).sum())}
    return out


def ablation_markdown(rows: dict, cfg, data, wall_seconds: float | None = None) -> str:
    names = list(rows)
    have_lpips = any(math.isfinite(_value(r, "latent", "lpips_ldr")) for r in rows.values())
    cols = [c for c in COLUMNS if have_lpips or c[1] != "lpips_ldr"]
    best = {}
    for section, key, _t, higher in cols:
        vals = {n: _value(rows[n], section, key) for n in names}
        finite = {n: v for n, v in vals.items() if math.isfinite(v)}
        if len(finite) > 1:
            best[(section, key)] = (max if higher else min)(finite, key=finite.get)
    first = rows[names[0]]
    n_lat = len(first.get("latent_per_image", []))
    n_ir = len(first.get("matte_per_scene", {}))
    n_lat_cols = sum(1 for c in cols if c[0] == "latent")
    lines = ["# Ablation of model components", "",
             f"| Ablation | Latent fitting ({n_lat} panoramas) |" + " |" * (n_lat_cols - 1)
             + f" Inverse rendering, matte ({n_ir} scene{'s' if n_ir != 1 else ''}) | | |",
             "| | " + " | ".join(t for _s, _k, t, _h in cols) + " |",
             "|---|" + "---:|" * len(cols)]
    for n in names:
        cells = []
        for section, key, _t, _h in cols:
            text = _fmt(_value(rows[n], section, key), key)
            cells.append(f"**{text}**" if best.get((section, key)) == n else text)
        lines.append(f"| {ROW_LABELS.get(n, n)} | " + " | ".join(cells) + " |")
    params = {n: rows[n].get("training", {}).get("parameters") for n in names}
    steps = {rows[n].get("training", {}).get("steps") for n in names}
    lines += ["", f"Every row: the `{cfg.preset}` preset, {'/'.join(str(s) for s in sorted(steps))} optimiser steps "
              f"(one equal budget: the same steps, batches and seed), lr {cfg.lr:g} after {cfg.warmup_steps} warm-up "
              f"steps, trained on `{data}`. Parameters: "
              + ", ".join(f"{ROW_LABELS.get(n, n)} {params[n]:,}" for n in names if params[n]) + ".",
              f"Latent fits: {cfg.fit_steps} Adam steps (paper: 1500) on held-out panoramas. Inverse rendering: the "
              f"`prior` method, {cfg.fit_iterations} iterations at {cfg.fit_spp} spp (paper: 500 at 64), "
              f"scored at {cfg.eval_spp} spp on {cfg.bench_image}×{cfg.bench_image} images of the silver-matte "
              "probe. Bold: the best of each column."
              + ("" if have_lpips else f" LPIPS is left out: {first.get('lpips') or 'not computed'}.")]
    if wall_seconds is not None:
        lines.append(f"Wall time of this call: {wall_seconds / 60:.1f} min.")
    paired = paired_to_full(rows)
    if paired:
        lines += ["", "## Difference to the full model", "",
                  f"Mean per-panorama (latent) or per-scene (matte) difference row − full [95 % bootstrap interval, "
                  f"{RESAMPLES} resamples], and how many the row does better on.", "",
                  "| Ablation | " + " | ".join(f"{'latent' if s == 'latent' else 'matte'} {t}" for s, k, t, _h in cols)
                  + " |", "|---|" + "---:|" * len(cols)]
        for n in names:
            if n not in paired:
                continue
            cells = []
            for section, key, _t, _h in cols:
                s = paired[n].get(f"{section}/{key}")
                if s is None:
                    cells.append("–")
                    continue
                lo, hi = s["ci95"]
                cells.append(f"{_fmt(s['mean'], key) if s['mean'] < 0 else '+' + _fmt(s['mean'], key)} "
                             f"[{_fmt(lo, key)}, {_fmt(hi, key)}] {s['better']}/{s['n']}")
            lines.append(f"| {ROW_LABELS.get(n, n)} | " + " | ".join(cells) + " |")
    lines += ["", "Figures: `figures/ablation.png` (each metric by row), `figures/latent-fits.png` "
              "(latent fits of two held-out panoramas by each row)."]
    return "\n".join(lines) + "\n"


def _figures(out: Path, rows: dict) -> list[Path]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from roomlight.core.color import MIDDLE_GREY, log_average_np, to_display
    fig_dir = out / "figures"
    fig_dir.mkdir(parents=True, exist_ok=True)
    names = list(rows)
    cols = [c for c in COLUMNS if any(math.isfinite(_value(r, c[0], c[1])) for r in rows.values())]
    fig, axes = plt.subplots(1, len(cols), figsize=(2.3 * len(cols), 3.2))
    for ax, (section, key, title, _h) in zip(np.atleast_1d(axes), cols):
        vals = [_value(rows[n], section, key) for n in names]
        ax.bar(range(len(names)), vals, color=["0.3"] + ["steelblue"] * (len(names) - 1))
        ax.set_xticks(range(len(names)))
        ax.set_xticklabels(names, rotation=70, fontsize=7)
        ax.set_title(f"{'latent' if section == 'latent' else 'matte'}\n{title}", fontsize=8)
        finite = [v for v in vals if math.isfinite(v)]
        if finite:
            lo, hi = min(finite), max(finite)
            pad = 0.15 * (hi - lo) if hi > lo else 0.05 * abs(hi) + 1e-6
            ax.set_ylim(lo - pad if lo - pad > 0 or lo < 0 else 0, hi + pad)
    fig.tight_layout()
    paths = []
    p = fig_dir / "ablation.png"
    fig.savefig(p, dpi=110)
    plt.close(fig)
    paths.append(p)

    examples = {}
    for n in names:
        f = out / "eval" / n / "latent_examples.npz"
        if f.is_file():
            with np.load(f) as z:
                examples[n] = {k: z[k] for k in z.files}
    if examples:
        first = next(iter(examples.values()))
        count = first["target_radiance"].shape[0]
        fig, axes = plt.subplots(len(examples) + 1, count, figsize=(3.2 * count, 1.7 * (len(examples) + 1)),
                                 squeeze=False)
        for c in range(count):
            target = first["target_radiance"][c]
            expo = MIDDLE_GREY / log_average_np(target)
            axes[0, c].imshow(to_display(target * expo))
            axes[0, c].set_title(str(first["names"][c]), fontsize=7)
            for r, n in enumerate(examples, start=1):
                axes[r, c].imshow(to_display(examples[n]["fit_radiance"][c] * expo))
            for r in range(len(examples) + 1):
                axes[r, c].set_xticks([])
                axes[r, c].set_yticks([])
                if c == 0:
                    axes[r, c].set_ylabel("target" if r == 0 else ROW_LABELS.get(list(examples)[r - 1], "")[:24],
                                          fontsize=7)
        fig.tight_layout()
        p = fig_dir / "latent-fits.png"
        fig.savefig(p, dpi=110)
        plt.close(fig)
        paths.append(p)
    return paths


def write_ablation_report(out, rows: dict, cfg, data, wall_seconds: float | None = None) -> dict:
    """Write ``ablation.md``, ``ablation.json`` and the figures; returns the summary dict."""
    from roomlight.evaluation.experiments.files import atomic_json, atomic_text

    out = Path(out)
    text = ablation_markdown(rows, cfg, data, wall_seconds)
    doc = {"settings": cfg.to_dict(), "data": str(data), "rows": rows, "paired_to_full": paired_to_full(rows),
           "wall_seconds": wall_seconds}
    atomic_json(out / "ablation.json", doc)
    figures = _figures(out, rows)
    atomic_text(out / "ablation.md", text)
    return {**doc, "markdown": text, "figures": [str(p) for p in figures]}
