"""Evaluating the prior as a model of panoramas (paper Tab. 1; docs/training.md).

For every panorama of an evaluation set, two reconstructions are scored:

- **encoder**: a single pass, z = posterior mean, decoded;
- **latent fit**: z optimised against the panorama with the decoder frozen
  (:func:`roomlight.prior.latent_fit.fit_latent`, the paper's 1500-step protocol by default).

Metrics (:mod:`roomlight.prior.eval.metrics`): PSNR, SSIM (and LPIPS when available locally) on
tone-mapped LDR, PSNR on linear HDR, the brightest pixel's error in stops, AbsRel on depth. The report is a dict (JSON) with means per
row and per-image values, and renders as a Markdown table.
"""

from __future__ import annotations

import json
import math
from functools import partial
from pathlib import Path

import torch

from roomlight.prior.data.dataset import collate_panoramas
from roomlight.errors import RoomlightError
from roomlight.prior.eval.lpips import load_lpips
from roomlight.core.color import to_display_at_key
from roomlight.prior.eval.metrics import abs_rel, peak_error_stops, psnr, psnr_hdr, ssim
from roomlight.prior.latent_fit.latent import LatentFitConfig, fit_latent
from roomlight.prior.latent_fit.pixel import fit_pixels

__all__ = ["METRICS", "metric_digits", "panorama_metrics", "evaluate_prior", "report_markdown", "write_report"]

#: Metric name -> (column title, higher is better).
METRICS = {
    "psnr_ldr": ("PSNR LDR ↑", True),
    "ssim_ldr": ("SSIM LDR ↑", True),
    "lpips_ldr": ("LPIPS LDR ↓", False),
    "psnr_hdr": ("PSNR HDR ↑", True),
    "peak_stops": ("Peak error (stops) ↓", False),
    "abs_rel": ("AbsRel depth ↓", False),
}


def metric_digits(name: str) -> int:
    """Decimals a table shows for metric ``name``: 4 for the small ratios (SSIM, LPIPS, AbsRel), else 2."""
    return 4 if name in ("ssim_ldr", "lpips_ldr", "abs_rel") else 2


def panorama_metrics(pred_radiance, pred_depth, radiance, depth, lpips_fn=None) -> dict[str, torch.Tensor]:
    """Per-image metrics of predictions against targets.

    Args:
        pred_radiance, radiance: (B, 3, H, W) linear radiance (same exposure scale).
        pred_depth, depth: (B, 1, H, W) radial depth, target > 0; either None (a radiance-only
            target or prior) leaves ``abs_rel`` out.
        lpips_fn: optional callable from :func:`roomlight.prior.eval.lpips.load_lpips`.
    Returns:
        name -> (B,) float64 tensor, names as in :data:`METRICS` (``lpips_ldr`` only with lpips_fn).
    """
    ldr_t = to_display_at_key(radiance.float())
    ldr_p = to_display_at_key(pred_radiance.float(), reference=radiance.float())
    out = {"psnr_ldr": psnr(ldr_p, ldr_t).cpu(), "ssim_ldr": ssim(ldr_p, ldr_t).cpu(),
           "psnr_hdr": psnr_hdr(pred_radiance, radiance).cpu(),
           "peak_stops": peak_error_stops(pred_radiance, radiance).cpu()}
    if depth is not None and pred_depth is not None:  # a radiance-only prior (VENI) decodes no depth
        out["abs_rel"] = abs_rel(pred_depth, depth).cpu()
    if lpips_fn is not None:
        out["lpips_ldr"] = lpips_fn(ldr_p, ldr_t)
    return out


def evaluate_prior(model, dataset, fit_config: LatentFitConfig | None = LatentFitConfig(), batch_size: int = 8,
                   depth_only_fit: bool = False, progress: bool = True, note=print,
                   radiance_only: bool = False, pixel_smoothness: float | None = None) -> dict:
    """Score encoder reconstructions and latent fits over ``dataset``.

    Args:
        model: a :class:`~roomlight.prior.model.PanoVAE` (eval mode is used).
        dataset: a :class:`~roomlight.prior.data.PanoramaDataset` at the model's resolution, with the
            model's exposure calibration and depth units.
        fit_config: latent-fit settings; None skips the latent-fit row.
        batch_size: panoramas processed together (latents are fitted independently).
        depth_only_fit: add a row "latent fit (depth only)" (the supplementary's AbsRel check).
        radiance_only: evaluate panoramas without depth (real captures): the encoder needs depth,
            so the only row is "latent fit (radiance)", z fitted to radiance alone (the dataset
            must be built with ``require_depth=False``); depth metrics are left out.
        pixel_smoothness: add the pixel-level rows "pixel level (HDR)" and "pixel level (HDRD)": a free
            panorama fitted with the latent fit's settings plus this smoothness weight
            (:func:`roomlight.prior.latent_fit.pixel.fit_pixels`); they need the latent fit. None: no such rows.
        note: receives messages (skipped files, LPIPS availability).

    A prior that decodes radiance only (VENI) has its latent fitted to the radiance (its rows carry
    no AbsRel).
    Returns:
        ``{"count", "rows": {row: {metric: mean}}, "per_image": [...], "skipped": [...],
        "lpips": None or reason, "fit": LatentFitConfig dict}``.
    """
    from roomlight.core.progress import progress_bar

    device = next(model.parameters()).device
    model.eval()
    lpips_fn, lpips_reason = load_lpips(device)
    if lpips_reason:
        note(lpips_reason)
    if radiance_only:
        if fit_config is None:
            raise RoomlightError("radiance-only evaluation needs the latent fit (fit steps > 0): "
                                 "the encoder needs depth")
        if fit_config.init_from_encoder:
            raise RoomlightError("radiance-only evaluation fits from z = 0: the encoder needs depth")
        rows = {"latent fit (radiance)": fit_config.override(target="radiance")}
    else:
        rows = {"encoder": None}
        has_depth = getattr(model, "has_depth", True)
        if fit_config is not None:
            rows["latent fit"] = fit_config if has_depth else fit_config.override(target="radiance")
            if depth_only_fit and not has_depth:
                raise RoomlightError("the depth-only fit needs a prior that decodes depth (this one is VENI)")
            if depth_only_fit:
                # Depth alone: no radiance, so no peak term and no encoder start (the encoder reads
                # radiance): the supplementary's check, from z = 0. The lone channel gets weight 1, which
                # is what any positive weight gives it, and keeps a --depth-weight 0 from emptying it.
                rows["latent fit (depth only)"] = fit_config.override(target="depth", peak_weight=0.0,
                                                                      depth_weight=1.0, init_from_encoder=False)
    pixel_rows = {}
    if pixel_smoothness is not None:
        if fit_config is None:
            raise RoomlightError("the pixel-level rows use the latent fit's settings: they need the latent fit")
        base = fit_config.override(init_from_encoder=False)
        pixel_rows = {"pixel level (HDR)": base.override(target="radiance")}
        if not radiance_only:
            pixel_rows["pixel level (HDRD)"] = base.override(target="both")
        rows.update(pixel_rows)
    per_image, skipped = [], []
    values: dict[str, dict[str, list]] = {r: {} for r in rows}
    # The bar counts work units: one per batch for the encoder pass, one per latent-fit step, so a
    # 1500-step fit moves it continuously instead of leaving it at 0 % for minutes.
    n_batches = math.ceil(len(dataset) / batch_size)
    per_batch = 1 + sum(cfg.steps for cfg in rows.values() if cfg is not None)
    bar = progress_bar(total=n_batches * per_batch, desc="eval-prior", unit="step", disable=not progress)
    done = 0
    for start in range(0, len(dataset), batch_size):
        batch = collate_panoramas([dataset[i] for i in range(start, min(start + batch_size, len(dataset)))])
        skipped += [{"name": n, "reason": r} for n, r in batch["skipped"]]
        for n, r in batch["skipped"]:
            note(f"skipping {n}: {r}")
        if batch["radiance"] is None:
            bar.update(per_batch)
            continue
        rad = batch["radiance"].to(device)
        dep = None if radiance_only or batch["depth"] is None else batch["depth"].to(device)
        if dep is None and not radiance_only:
            raise RoomlightError(f"{', '.join(batch['names'])}: no depth; evaluate radiance-only "
                                 "panoramas with --radiance-only")
        records = [{"name": n} for n in batch["names"]]
        for row, cfg in rows.items():
            if cfg is None:
                with torch.no_grad():
                    pr, pd = model.decode(model.encode(rad, dep).mean)
                bar.update(1)
            else:
                bar.set_postfix_str(f"{row}, panoramas {done}-{done + len(batch['names'])} of {len(dataset)}")
                fit = (partial(fit_pixels, normalization=model.normalization, smoothness_weight=pixel_smoothness)
                       if row in pixel_rows else partial(fit_latent, model))
                res = fit(rad if cfg.target != "depth" else None, dep if cfg.target != "radiance" else None, cfg,
                          callback=lambda step, loss: bar.update(1))
                pr, pd = res.radiance, res.depth
            m = panorama_metrics(pr, pd, rad, dep, lpips_fn)
            for k, v in m.items():
                values[row].setdefault(k, []).extend(v.tolist())
                for rec, val in zip(records, v.tolist()):
                    rec.setdefault(row, {})[k] = val
        per_image += records
        done += len(batch["names"]) + len(batch["skipped"])
    bar.close()
    means = {row: {k: _mean(v) for k, v in vals.items()} for row, vals in values.items()}
    return {"count": len(per_image), "rows": means, "per_image": per_image, "skipped": skipped,
            "lpips": lpips_reason, "fit": fit_config.to_dict() if fit_config is not None else None,
            "pixel_smoothness": pixel_smoothness}


def _mean(v: list) -> float:
    finite = [x for x in v if math.isfinite(x)]
    return sum(finite) / len(finite) if finite else math.nan


def _finite_or_none(obj):
    """Replace NaN/inf by None recursively: strict JSON has no such numbers."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: _finite_or_none(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_finite_or_none(v) for v in obj]
    return obj


def report_markdown(report: dict, title: str = "Prior evaluation") -> str:
    """The report's means as a Markdown table (rows: encoder / latent fit; columns: metrics)."""
    cols = [k for k in METRICS if any(k in r for r in report["rows"].values())]
    lines = [f"## {title}", "", f"{report['count']} panoramas"
             + (f", {len(report['skipped'])} skipped" if report["skipped"] else "") + ".", ""]
    lines.append("| | " + " | ".join(METRICS[k][0] for k in cols) + " |")
    lines.append("|---|" + "---:|" * len(cols))
    for row, vals in report["rows"].items():
        cells = [f"{vals[k]:.{metric_digits(k)}f}" if k in vals else "—" for k in cols]
        lines.append(f"| {row} | " + " | ".join(cells) + " |")
    lines.append("")
    if report.get("lpips"):
        lines.append(f"{report['lpips']}.")
    if report.get("fit"):
        # Reports written before the objective had weights lack those fields: their defaults apply.
        known = {k: v for k, v in report["fit"].items() if k in LatentFitConfig.__dataclass_fields__}
        lines.append(f"Latent fit: {LatentFitConfig(**known).describe()}.")
    if report.get("pixel_smoothness") is not None:
        lines.append(f"Pixel level: a free normalised panorama, the latent fit's optimiser and objective from the mean "
                     f"panorama, plus {report['pixel_smoothness']:g} × the smoothness prior per channel and pixel; "
                     "no bottleneck, so these rows measure that regularisation, not a representation.")
    lines.append("LDR: exposure so that the target's log-average luminance is 0.18, clip, gamma 2.2. "
                 "HDR PSNR: peak = the target's maximum. Peak error: |log2| of the ratio of the brightest "
                 "pixels' luminances (the strongest light). AbsRel: mean |D̂ − D| / D.")
    return "\n".join(lines) + "\n"


def write_report(report: dict, out_dir: str | Path, stem: str = "eval_prior") -> tuple[Path, Path]:
    """Write ``{stem}.md`` and ``{stem}.json`` into ``out_dir``; returns both paths."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    md, js = out / f"{stem}.md", out / f"{stem}.json"
    md.write_text(report_markdown(report))
    js.write_text(json.dumps(_finite_or_none(report), indent=2) + "\n")
    return md, js
