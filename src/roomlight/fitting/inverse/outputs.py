"""Files a fit leaves behind: recovered panorama, emitter bundle, history, plots, previews."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import torch

from roomlight.core.render.variant import thread_record

__all__ = ["write_fit_outputs", "plot_history", "light_summary", "extreme_light_note", "recorded_light_note", "EXTREME_CONTRAST"]

#: Brightest texel over median luminance above which a recovered light is flagged. The 2400
#: procedural training rooms of the bundled prior reach at most 14,791x their log-average
#: luminance (about their median), and a fit sees a texel only through the few pixels that
#: reflect it: the image loss censors renders at the target's clipping level, so a texel seen
#: only in saturated pixels can grow without bound (a mirror fit grew one to 172,788 in a room
#: whose brightest value is 71). A real sun can exceed this too, hence a note, not an error.
EXTREME_CONTRAST = 1e5


def light_summary(radiance: torch.Tensor) -> dict:
    """Brightness of a recovered light, recorded as ``light`` in ``result.json``.

    Args:
        radiance: (H, W, 3) linear radiance (exposure applied).
    Returns:
        ``peak_luminance`` and ``median_luminance`` (Rec. 709), ``peak_contrast`` (their ratio,
        as :func:`roomlight.prior.eval.metrics.peak_contrast`) and ``extreme`` (contrast above
        :data:`EXTREME_CONTRAST`).
    """
    from roomlight.core.color import peak_and_median_luminance

    peak, median = (float(v[0]) for v in peak_and_median_luminance(radiance.detach().permute(2, 0, 1)[None]))
    contrast = peak / max(median, 1e-12)
    return {"peak_luminance": peak, "median_luminance": median, "peak_contrast": contrast,
            "extreme": contrast > EXTREME_CONTRAST}


def extreme_light_note(summary: dict) -> str | None:
    """One line for the user when :func:`light_summary` flags the light, else None."""
    if not summary["extreme"]:
        return None
    return (f"note: the recovered light's brightest texel is {summary['peak_contrast']:.3g}x its median luminance; "
            "a texel that bright is usually one the view did not constrain (its reflection fell on saturated "
            "pixels): look at preview.png and panorama.exr before rendering with it")


def recorded_light_note(result_json: Path) -> str | None:
    """:func:`extreme_light_note` for the ``light`` a fit recorded in its ``result.json``.

    The command line reads the summary back rather than measuring the light again, so the note
    and the file cannot disagree.
    """
    return extreme_light_note(json.loads(Path(result_json).read_text())["light"])


def plot_history(history: list[dict], path: Path, title: str = "") -> None:
    """Loss curve PNG: per-iteration total loss and the fixed-seed checks (log scale)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    its = [h["iteration"] for h in history if "total" in h]
    fig, ax = plt.subplots(figsize=(6.4, 3.6), dpi=110)
    if its:
        ax.plot(its, [h["total"] for h in history if "total" in h], lw=0.8, alpha=0.7, label="total (per-step seed)")
        ax.plot(its, [h["img"] for h in history if "total" in h], lw=0.8, alpha=0.7, label="image term")
    checks = [(h["iteration"], h["fixed_seed_loss"]) for h in history if "fixed_seed_loss" in h]
    if checks:
        ax.plot(*zip(*checks), "o-", ms=3, lw=1.2, label="total (fixed seed)")
    ax.set_yscale("log")
    ax.set_xlabel("iteration")
    ax.set_ylabel("loss")
    ax.set_title(title)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def write_fit_outputs(out: Path, result, fitter, target: torch.Tensor, mask: torch.Tensor) -> dict[str, Path]:
    """Write ``panorama.exr`` (R,G,B,Z), ``emitter/`` (PLY + Mitsuba XML), ``loss.png``,
    ``preview.png`` (target | render under the recovered light | masked error) and ``result.json``."""
    from roomlight.core.emitter.export import export_emitter
    from roomlight.core.io import save_png, write_panorama
    from roomlight.core.io.preview import tonemap_gamma

    out = Path(out)
    paths = {"history": out / "history.jsonl"}
    rad = result.radiance
    paths["panorama"] = out / "panorama.exr"
    write_panorama(paths["panorama"], (rad.numpy(), result.depth.numpy() if result.depth is not None else None),
                   half=False, metadata={"method": result.method, "emitter_kind": result.emitter_kind})
    export_emitter(out / "emitter", rad, result.depth, result.emitter_kind, metadata={"method": result.method})
    paths["emitter"] = out / "emitter"
    paths["loss"] = out / "loss.png"
    plot_history(result.history, paths["loss"], title=result.method)
    with torch.no_grad():
        fitter.escene.set_emitter(rad, result.depth)
        img = fitter.escene.render(spp=max(fitter.config.spp, 64), seed=7)
    err = (img - target).abs().mean(-1) * mask
    err_img = np.clip(err.numpy() / max(float(err.max()), 1e-6), 0, 1)
    err_rgb = (np.stack([err_img, err_img ** 2, np.zeros_like(err_img)], -1) * 255).astype(np.uint8)
    strip = np.concatenate([tonemap_gamma(target.numpy()), tonemap_gamma(img.numpy()), err_rgb], axis=1)
    paths["preview"] = out / "preview.png"
    save_png(paths["preview"], strip)
    summary = {"method": result.method, "emitter_kind": result.emitter_kind, "best_iteration": result.best_iteration,
               "best_fixed_seed_loss": result.best_loss, "seconds": round(result.seconds, 3),
               "nonfinite_steps": result.nonfinite_steps, "light": light_summary(rad),
               "light_parameters": fitter.light.describe(), "config": result.config, "threads": thread_record(),
               "files": {k: str(v.relative_to(out)) for k, v in paths.items()}}
    paths["result"] = out / "result.json"
    paths["result"].write_text(json.dumps(summary, indent=2))
    return paths
