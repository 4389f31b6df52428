"""``roomlight experiment ablate``: the paper's ablation table (supplementary, Tab. "Ablation").

Six priors are trained on the same data with the same schedule (the same number of optimiser
steps, the same seed, hence the same batches): the full model, and the model without

- the peak loss (``loss.peak = 0``),
- the Scharr gradient terms (``loss.grad_radiance = loss.grad_depth = 0``),
- AdaGN in the decoder (``ModelConfig.adagn = False``: affine GroupNorms, z enters only through
  the decoder's first linear layer),
- the latitude channels (``ModelConfig.latitude = False``),
- all four at once.

Each is then scored on **latent fitting** (:func:`roomlight.prior.eval.prior.evaluate_prior`: z fitted
to held-out panoramas with the decoder frozen; PSNR / SSIM / LPIPS on LDR, PSNR on HDR, depth
AbsRel) and on **matte inverse rendering** (the synthetic benchmark of :mod:`roomlight.evaluation.bench`
built once from the held-out panoramas with the silver-matte material; the ``prior`` method fitted
with each model; PSNR LDR, RMSE HDR and RGB angular error of the evaluation probe).

Layout of ``OUT`` (every stage resumes; a finished stage is skipped)::

    OUT/settings.json            the AblationConfig (a resume with other settings is refused)
    OUT/data/                    procedural rooms, when no --data is given (roomlight synth)
    OUT/runs/<row>/              a training run (roomlight train layout); done.json when finished
    OUT/bench/                   the matte benchmark scenes (roomlight bench make)
    OUT/eval/<row>/              eval_prior.json, bench/ (bench run results), row.json (done)
    OUT/ablation.md, ablation.json, figures/ablation.png, figures/latent-fits.png
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from roomlight.core.config import StrictConfig
from roomlight.errors import RoomlightError
from roomlight.evaluation.harness.records import check_settings
from roomlight.evaluation.experiments.ablation_rows import ROW_LABELS, ROWS
from roomlight.evaluation.experiments.files import atomic_json

__all__ = ["AblationConfig", "ABLATION_PRESETS", "row_train_config", "run_ablation"]

@dataclass(frozen=True)
class AblationConfig(StrictConfig):
    """Settings of the ablation study (one equal training budget for every row)."""

    preset: str = "lite"              #: training + model preset of every row (roomlight train --config)
    steps: int = 1000                 #: optimiser steps per row (0: the preset's own epochs)
    lr: float = 1e-3                  #: peak learning rate (the bundled prior's CPU recipe)
    warmup_steps: int = 100           #: learning-rate warm-up steps
    batch_size: int = 0               #: batch size (0: the preset's)
    seed: int = 0                     #: seed of the weights, data order and augmentation; first room seed
    rows: tuple[str, ...] = tuple(ROWS)  #: which rows to train and score
    synth_rooms: int = 600            #: rooms rendered when no data folder is given (80/10/10 split)
    synth_spp: int = 64               #: samples per pixel of those rooms (a perfect square)
    eval_panoramas: int = 16          #: held-out panoramas for the latent fits
    fit_steps: int = 500              #: latent-fit iterations (paper: 1500)
    bench_scenes: int = 8             #: held-out panoramas turned into matte benchmark scenes
    bench_image: int = 96             #: benchmark image size (square)
    bench_spp: int = 256              #: ground-truth spp of the benchmark renders
    fit_iterations: int = 100         #: inverse-rendering iterations per scene (paper: 500)
    fit_spp: int = 16                 #: samples per pixel per fitting step (paper: 64)
    eval_spp: int = 256               #: samples per pixel of the scoring re-renders (paper: 4096)

    def __post_init__(self):
        from roomlight.prior.train.config import get_train_preset

        get_train_preset(self.preset)
        object.__setattr__(self, "rows", tuple(self.rows))
        bad = [r for r in self.rows if r not in ROWS]
        if bad or not self.rows:
            raise RoomlightError(f"ablate: unknown row(s) {', '.join(bad) or '(none)'}; choose from {', '.join(ROWS)}")
        for name in ("eval_panoramas", "bench_scenes", "bench_image", "bench_spp", "fit_spp", "eval_spp",
                     "synth_rooms", "synth_spp"):
            if getattr(self, name) < 1:
                raise RoomlightError(f"ablate: {name} must be >= 1, got {getattr(self, name)}")
        for name in ("steps", "fit_steps", "fit_iterations", "warmup_steps", "batch_size"):
            if getattr(self, name) < 0:
                raise RoomlightError(f"ablate: {name} must be >= 0, got {getattr(self, name)}")


#: ``cpu``: the whole study in about two hours on a 2-core CPU (lite network,
#: 64 x 128); ``paper``: the paper's network and schedule (a GPU); ``tiny``: a smoke test.
ABLATION_PRESETS: dict[str, AblationConfig] = {
    "cpu": AblationConfig(),
    "paper": AblationConfig(preset="default", steps=0, lr=2e-4, warmup_steps=250, synth_rooms=2500, synth_spp=144,
                            eval_panoramas=25, fit_steps=1500, bench_scenes=25, bench_image=256, bench_spp=1024,
                            fit_iterations=500, fit_spp=64, eval_spp=1024),
    "tiny": AblationConfig(preset="tiny", steps=30, lr=2e-3, warmup_steps=5, synth_rooms=10, synth_spp=16,
                           eval_panoramas=2, fit_steps=20, bench_scenes=1, bench_image=32, bench_spp=16,
                           fit_iterations=2, fit_spp=4, eval_spp=16),
}


def row_train_config(cfg: AblationConfig, row: str, progress: bool = True):
    """The :class:`~roomlight.prior.train.TrainConfig` of one row: the preset, the shared schedule, the
    row's loss and model overrides."""
    from roomlight.prior.train.config import get_train_preset

    loss, model = ROWS[row]
    base = get_train_preset(cfg.preset)
    changes = dict(lr=cfg.lr, min_lr=min(base.min_lr, cfg.lr), warmup_steps=cfg.warmup_steps, seed=cfg.seed,
                   num_workers=0, progress=progress, loss=loss, model_overrides=model, image_every=0)
    if cfg.steps:
        changes.update(max_steps=cfg.steps, ckpt_every=max(1, min(base.ckpt_every, cfg.steps // 4 or 1)),
                       val_every=max(1, cfg.steps // 5))
    if cfg.batch_size:
        changes["batch_size"] = cfg.batch_size
    return base.replace(**changes)


def _check_settings(out: Path, cfg: AblationConfig, data: str) -> None:
    check_settings(out / "settings.json", {"config": cfg.to_dict(), "data": data})


def _prepare_data(out: Path, cfg: AblationConfig, data, note) -> Path:
    """The data folder: the given one, or procedural rooms rendered into OUT/data at the preset's resolution."""
    if data is not None:
        return Path(data)
    from roomlight.datagen.synth.dataset import SynthConfig, generate_dataset
    from roomlight.prior.train.config import get_train_preset

    h = get_train_preset(cfg.preset).model_config.resolution[0]
    note(f"rendering {cfg.synth_rooms} rooms at {h}x{2 * h} into {out / 'data'}")
    generate_dataset(out / "data", SynthConfig(n=cfg.synth_rooms, seed0=cfg.seed, height=h, spp=cfg.synth_spp),
                     progress=True)
    return out / "data"


def _held_out(data: Path) -> list[Path]:
    from roomlight.prior.data import split_files

    splits = split_files(data)
    files = splits["test"] or splits["val"]
    if not files:
        raise RoomlightError(f"{data}: no test/ or validation panoramas to evaluate the ablations on")
    return files


def _train_row(out: Path, cfg: AblationConfig, row: str, data: Path, progress: bool, note) -> dict:
    from roomlight.prior.train import Trainer

    run = out / "runs" / row
    done = run / "done.json"
    if done.is_file():
        return json.loads(done.read_text())
    tcfg = row_train_config(cfg, row, progress)
    note(f"training row {row} ({ROW_LABELS[row]}) in {run}")
    t0 = time.perf_counter()
    trainer = Trainer(tcfg, data, run, note=note)
    try:
        summary = trainer.fit()
    finally:
        trainer.close()
    if summary["step"] < summary["total_steps"]:
        raise RoomlightError(f"{run}: training stopped at step {summary['step']} of {summary['total_steps']}")
    params = sum(p.numel() for p in trainer.model.parameters())
    rec = {"row": row, "steps": summary["step"], "seconds_this_sitting": round(time.perf_counter() - t0, 1),
           "parameters": int(params), "best_val_loss": summary["best"], "train": summary["train"]}
    atomic_json(done, rec)
    return rec


def _bench(out: Path, cfg: AblationConfig, held_out: list[Path], resolution, progress: bool) -> Path:
    from roomlight.evaluation.bench.builder import BenchConfig, make_benchmark

    bench = out / "bench"
    panos = held_out[0].parent
    bcfg = BenchConfig(n=cfg.bench_scenes, seed=cfg.seed, emitter_height=int(resolution[0]), width=cfg.bench_image,
                       height=cfg.bench_image, spp=cfg.bench_spp, materials=("matte",))
    make_benchmark(panos, bench, bcfg, progress=progress)
    return bench


def _evaluate_row(out: Path, cfg: AblationConfig, row: str, data: Path, held_out: list[Path], bench: Path,
                  progress: bool, note) -> dict:
    from roomlight.evaluation.bench.report import collect_results
    from roomlight.evaluation.bench.runner import run_benchmark
    from roomlight.prior.data import PanoramaDataset
    from roomlight.prior.eval.prior import evaluate_prior, write_report
    from roomlight.prior.latent_fit import LatentFitConfig
    from roomlight.fitting.inverse import fit_config
    from roomlight.prior.model.runs import load_run_model
    from roomlight.core.render.variant import torch_device

    edir = out / "eval" / row
    done = edir / "row.json"
    if done.is_file():
        return json.loads(done.read_text())
    edir.mkdir(parents=True, exist_ok=True)
    run = out / "runs" / row
    t0 = time.perf_counter()
    latent_file = edir / "eval_prior.json"
    if latent_file.is_file():
        latent = json.loads(latent_file.read_text())
    else:
        note(f"latent fits of row {row}")
        model = load_run_model(run)
        ds = PanoramaDataset(held_out[:cfg.eval_panoramas], model.config.resolution, root=data, calibrate=True,
                             depth_units=model.metadata.get("depth_units", "metres"))
        latent = evaluate_prior(model, ds, LatentFitConfig(steps=cfg.fit_steps), batch_size=8, progress=progress,
                                note=note)
        _latent_examples(model, ds, cfg, edir / "latent_examples.npz")
        write_report(latent, edir)  # eval_prior.md / .json (written last: marks the stage done)
        latent = json.loads(latent_file.read_text())
    note(f"matte inverse rendering of row {row}")
    model = load_run_model(run, device=torch_device())
    fcfg = fit_config("fast", iterations=cfg.fit_iterations, spp=cfg.fit_spp)
    summary = run_benchmark(bench, edir / "bench", ["prior"], fcfg, model, eval_spp=cfg.eval_spp, progress=progress,
                            model_name=str(run.resolve()))
    if summary.failed:
        raise RoomlightError(f"row {row}: {len(summary.failed)} benchmark case(s) failed: "
                             + "; ".join(f"{k}: {v}" for k, v in summary.failed.items()))
    records = collect_results(edir / "bench")
    per_scene = {r["scene"]: r["metrics"]["eval"] for r in records if r["method"] == "prior"}
    rec = {"row": row, "label": ROW_LABELS[row],
           "latent": latent["rows"]["latent fit"], "latent_per_image": [
               {"name": p["name"], **p["latent fit"]} for p in latent["per_image"]],
           "lpips": latent.get("lpips"),
           "matte": {k: float(np.mean([m[k] for m in per_scene.values()])) for k in ("psnr_ldr", "rmse_hdr",
                                                                                   "angular_error")},
           "matte_per_scene": per_scene, "eval_seconds": round(time.perf_counter() - t0, 1)}
    atomic_json(done, rec)
    return rec


def _latent_examples(model, ds, cfg: AblationConfig, path: Path, count: int = 2) -> None:
    """Latent fits of the first ``count`` held-out panoramas, kept for the figure (radiance and
    depth of target and fit, (count, H, W, 3) and (count, H, W))."""
    import torch

    from roomlight.prior.data.dataset import collate_panoramas
    from roomlight.prior.latent_fit import LatentFitConfig, fit_latent

    batch = collate_panoramas([ds[i] for i in range(min(count, len(ds)))])
    if batch["radiance"] is None:
        return
    device = next(model.parameters()).device
    rad, dep = batch["radiance"].to(device), batch["depth"].to(device)
    res = fit_latent(model, rad, dep, LatentFitConfig(steps=cfg.fit_steps))
    with torch.no_grad():
        arrays = {"target_radiance": rad.permute(0, 2, 3, 1), "target_depth": dep[:, 0],
                  "fit_radiance": res.radiance.permute(0, 2, 3, 1), "fit_depth": res.depth[:, 0]}
        arrays = {k: v.detach().float().cpu().numpy() for k, v in arrays.items()}
    tmp = path.with_name(f".{path.stem}.tmp.npz")
    np.savez_compressed(tmp, names=np.asarray(batch["names"]), **arrays)
    tmp.replace(path)


def run_ablation(out_dir, cfg: AblationConfig = AblationConfig(), data=None, progress: bool = True,
                 note=print) -> dict:
    """Train, evaluate and tabulate every row of ``cfg.rows`` (resumable); returns the summary.

    Args:
        data: a panorama folder with ``train/`` and ``val/`` (and ``test/``) sub-folders, as
            ``roomlight synth`` writes; default: ``cfg.synth_rooms`` procedural rooms rendered
            into ``OUT/data``.
    """
    from roomlight.evaluation.experiments.ablation_report import write_ablation_report
    from roomlight.prior.train.config import get_train_preset

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    _check_settings(out, cfg, str(Path(data).resolve()) if data is not None else "OUT/data")
    t0 = time.perf_counter()
    data = _prepare_data(out, cfg, data, note)
    held_out = _held_out(data)
    resolution = get_train_preset(cfg.preset).model_config.resolution
    trained = {row: _train_row(out, cfg, row, data, progress, note) for row in cfg.rows}
    bench = _bench(out, cfg, held_out, resolution, progress)
    rows = {row: _evaluate_row(out, cfg, row, data, held_out, bench, progress, note) for row in cfg.rows}
    for row in rows:
        rows[row]["training"] = trained[row]
    return write_ablation_report(out, rows, cfg, data, wall_seconds=time.perf_counter() - t0)
