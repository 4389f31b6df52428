"""Training loop of the prior (paper §3.3, supp. "Training details"; docs/training.md).

``Trainer(config, data_dir, run_dir).fit()`` trains a :class:`~roomlight.prior.model.PanoVAE` and is
*exactly* resumable: constructing a Trainer on a run folder that has checkpoints restores the
model, AdamW moments, step, schedule length, number of batches drawn (which fixes the data
order, see :class:`~roomlight.prior.data.ResumableBatchSampler`) and every random generator
(augmentation, posterior sampling, torch's global one), so N steps, a restart and N more give
the same weights as 2N uninterrupted steps.

Run folder layout::

    RUN/train_config.json       the TrainConfig (checked on resume) and the data folder
    RUN/normalization.json      statistics of the training split (stored in the model too)
    RUN/log.jsonl               one JSON object per event; RUN/tensorboard/ if installed
    RUN/checkpoints/step-N/     resumable checkpoints (see roomlight.prior.train.checkpoint)
    RUN/best/                   the model with the lowest validation loss (from_pretrained)
    RUN/images/step-N.png       inputs | reconstructions | samples panels
"""

from __future__ import annotations

import json
import math
import shutil
import time
from contextlib import nullcontext
from pathlib import Path

import torch
from torch.utils.data import DataLoader

from roomlight.prior.data import (PackedCache, PanoramaDataset, ResumableBatchSampler, augment_batch, collate_panoramas,
                            normalization_from_dataset, split_files)
from roomlight.errors import RoomlightError
from roomlight.prior.losses import vae_loss
from roomlight.prior.model import Normalization, PanoVAE
from roomlight.prior.model.families import build_model
from roomlight.prior.model.grow import can_grow, grow_latent_state
from roomlight.prior.train import checkpoint as ck
from roomlight.prior.train.config import TrainConfig, config_differences
from roomlight.prior.train.distributed import all_reduce_mean, barrier, broadcast_flag, init_distributed
from roomlight.prior.train.interrupt import Interrupted, checkpoint_interrupted, deferred_interrupts
from roomlight.prior.train.logger import RunLogger
from roomlight.prior.train.schedule import learning_rate

__all__ = ["Trainer", "TrainingError"]

LOSS_TERMS = ("total", "l1_radiance", "l1_depth", "grad_radiance", "grad_depth", "peak", "kl")


class TrainingError(RoomlightError):
    """Training cannot go on (non-finite loss or gradient); the message says where and what to do."""


class Trainer:
    """Trains the prior on a folder of panoramas; see the module docstring.

    Args:
        config: the run's :class:`TrainConfig`.
        data_dir: panorama folder (``train/``/``val/`` sub-folders, or one folder split by hash).
        run_dir: output folder; if it holds checkpoints the run resumes from the newest one.
        device: ``cpu``/``cuda``; default CUDA when available.
        note: receives one-line human messages (default: ``tqdm.write`` on rank 0).
    """

    def __init__(self, config: TrainConfig, data_dir, run_dir, device: str | None = None, note=None):
        from tqdm import tqdm

        self.cfg = config
        self.data_dir, self.run_dir = Path(data_dir), Path(run_dir)
        self.dist = init_distributed(device)
        self.device = self.dist.device
        main = self.dist.is_main
        self.note = note if note is not None else (tqdm.write if main else (lambda *_: None))
        self.run_dir.mkdir(parents=True, exist_ok=True)
        fresh = self._check_config()
        self._setup_data()
        self._setup_model()
        self.step, self.position, self.best = 0, 0, math.inf
        self.last_checkpoint: Path | None = None
        self.total_steps = config.max_steps or config.epochs * self.sampler.batches_per_epoch
        latest = ck.latest_checkpoint(self.run_dir)
        resume_step = None
        if latest is not None:
            self._resume(latest)
            resume_step = self.step
        elif (self.run_dir / "log.jsonl").exists():
            # An earlier process stopped (killed) before its first checkpoint: nothing to resume,
            # and its log lines go, so that the log holds each step once.
            self.note(f"{self.run_dir}: no checkpoint to resume from; starting afresh at step 0")
            resume_step = -1
        self.log = RunLogger(self.run_dir, enabled=main, resume_step=resume_step, note=self.note)
        self._reported: set[str] = set()
        if fresh and main:  # recorded only once the data and model are set up, so a failed start binds nothing
            from roomlight import __version__

            ck.atomic_write_text(self.run_dir / "train_config.json", json.dumps(
                {"config": self.cfg.to_dict(), "data": str(self.data_dir.resolve()),
                 "roomlight_version": __version__}, indent=2) + "\n")

    # ------------------------------------------------------------------ setup
    def _check_config(self) -> bool:
        """Refuse a resume with a different recipe; True when the run is new."""
        path = self.run_dir / "train_config.json"
        if path.exists():
            saved = json.loads(path.read_text())
            diffs = config_differences(TrainConfig.from_dict(saved["config"]), self.cfg)
            if diffs:
                raise RoomlightError(
                    f"{self.run_dir}: cannot resume, the run was started with a different configuration; "
                    f"differing fields: {'; '.join(diffs)}. Rerun with the original settings, or pass a new --out"
                )
            if saved.get("data") != str(self.data_dir.resolve()):
                self.note(f"note: this run was started on {saved.get('data')}, now reading {self.data_dir.resolve()}")
            return False
        return True

    def _setup_data(self) -> None:
        cfg, res = self.cfg, self.cfg.model_config.resolution
        splits = split_files(self.data_dir, cfg.val_fraction)
        if not splits["train"]:
            raise RoomlightError(f"{self.data_dir}: no training panoramas (the train split is empty)")
        cache = None
        if cfg.cache:
            files = splits["train"] + splits["val"]
            path = self._cache_path()
            pack = dict(path=path, dtype=cfg.cache_dtype, calibrate=cfg.calibrate, depth_units=cfg.depth_units,
                        clamp_negative=cfg.clamp_negative, fill_nonfinite=cfg.fill_nonfinite)
            if self.dist.is_main:
                PackedCache.open_or_build(self.data_dir, files, res, workers=cfg.num_workers, progress=cfg.progress,
                                          log=self.note, **pack)
            barrier(self.dist)
            cache = PackedCache.open_or_build(self.data_dir, files, res, progress=False, **pack)
        kw = dict(root=self.data_dir, calibrate=cfg.calibrate, depth_units=cfg.depth_units, cache=cache,
                  clamp_negative=cfg.clamp_negative, fill_nonfinite=cfg.fill_nonfinite)
        self.train_set = PanoramaDataset(splits["train"], res, **kw)
        self.val_set = PanoramaDataset(splits["val"], res, **kw) if splits["val"] else None
        batch = cfg.batch_size
        if batch > len(self.train_set):
            batch = len(self.train_set)
            self.note(f"note: only {batch} training panoramas, so batches hold {batch} instead of {cfg.batch_size}")
        self.sampler = ResumableBatchSampler(len(self.train_set), batch, cfg.seed, rank=self.dist.rank,
                                             world_size=self.dist.world_size)

    def _cache_path(self) -> Path:
        from roomlight.prior.data.cache import default_cache_path

        cfg = self.cfg
        path = default_cache_path(self.data_dir, self.cfg.model_config.resolution, cfg.cache_dtype,
                                  cfg.calibrate, cfg.depth_units)
        try:  # the data folder may be read-only: then the cache lives in the run folder
            path.parent.mkdir(parents=True, exist_ok=True)
            probe = path.parent / f".write-test-{id(self)}"
            probe.touch()
            probe.unlink()
            return path
        except OSError:
            return self.run_dir / "cache" / path.name

    def _setup_model(self) -> None:
        cfg = self.cfg
        norm_path = self.run_dir / "normalization.json"
        source = self._init_source() if cfg.init_from else None
        if source is not None and not norm_path.exists() and self.dist.is_main:
            self.note(f"starting from the weights of {cfg.init_from}, with its normalisation statistics")
            ck.atomic_write_text(norm_path, json.dumps(source.normalization.to_dict(), indent=2) + "\n")
        if not norm_path.exists() and self.dist.is_main:
            self.note(f"computing normalisation statistics over {len(self.train_set)} training panoramas")
            from roomlight.prior.data.stats import NoUsablePanorama

            try:
                norm, skipped = normalization_from_dataset(self.train_set, progress=cfg.progress)
            except NoUsablePanorama as exc:
                for name, why in exc.skipped:
                    self.note(f"skipping {name}: {why}")
                raise RoomlightError(f"no usable panorama in {self.data_dir}") from None
            for name, why in skipped:
                self.note(f"skipping {name}: {why}")
            ck.atomic_write_text(norm_path, json.dumps(norm.to_dict(), indent=2) + "\n")
        barrier(self.dist)
        norm = Normalization.from_dict(json.loads(norm_path.read_text()))
        torch.manual_seed(cfg.seed)  # identical initial weights on every rank and every fresh run
        self.model = build_model(cfg.model_config, norm, {"depth_units": cfg.depth_units, "source": "roomlight train"})
        if source is not None:  # a resumed run overwrites these with its checkpoint's weights
            state = source.state_dict()
            if source.config != self.model.config:  # a larger latent (checked by _init_source)
                gen = torch.Generator().manual_seed(cfg.seed * 7919 + 303)
                state = grow_latent_state(state, source.config, self.model.config, generator=gen)
                self.note(f"grew the latent from {source.config.latent_dim} to {self.model.config.latent_dim} "
                          f"dimensions; the network starts out computing what {cfg.init_from} computes")
            self.model.load_state_dict(state)
        self.model.to(self.device)
        cuda = self.device.type == "cuda"
        self.amp = cfg.amp == "bf16" or (cfg.amp == "auto" and cuda)
        if cfg.compile == "on" or (cfg.compile == "auto" and cuda):
            # Module.compile() keeps the parameter names, so checkpoints stay loadable everywhere.
            for child in self.model.children():  # encoder and decoder (VENI: encoder and field)
                child.compile()
        self.ddp = self.model
        if self.dist.distributed:
            from torch.nn.parallel import DistributedDataParallel

            self.ddp = DistributedDataParallel(self.model, device_ids=[self.device.index] if cuda else None)
        self.optimizer = torch.optim.AdamW(self.model.parameters(), lr=cfg.lr, betas=cfg.betas,
                                           weight_decay=cfg.weight_decay)
        rank = self.dist.rank
        self.aug_gen = torch.Generator().manual_seed(cfg.seed * 7919 + 101 + rank)
        self.sample_gen = torch.Generator(device=self.device).manual_seed(cfg.seed * 7919 + 202 + rank)

    def _init_source(self) -> PanoVAE:
        """The model named by ``init_from``, checked against this run's architecture."""
        from roomlight.prior.model.runs import load_run_model

        source = load_run_model(self.cfg.init_from, device="cpu")
        if source.config != self.cfg.model_config and not can_grow(source.config, self.cfg.model_config):
            raise RoomlightError(
                f"init_from {self.cfg.init_from}: its architecture differs from the {self.cfg.model!r} preset "
                f"this run trains; pass the preset it was trained with (--config), changing at most a larger "
                f"latent_dim (--set model_overrides.latent_dim=N)")
        if source.normalization is None:
            raise RoomlightError(f"init_from {self.cfg.init_from}: the model has no normalisation statistics")
        return source

    # ------------------------------------------------------------------ state
    def _rng_state(self) -> dict[str, torch.Tensor]:
        rng = {"torch": torch.get_rng_state(), "aug": self.aug_gen.get_state(), "sample": self.sample_gen.get_state()}
        if torch.cuda.is_available():
            dev = self.device if self.device.type == "cuda" else "cuda"
            rng["cuda"] = torch.cuda.get_rng_state(dev)
        return rng

    def _trainer_state(self) -> dict:
        return {"step": self.step, "position": self.position, "epoch": self.sampler.epoch_of(self.position),
                "total_steps": self.total_steps, "best": None if math.isinf(self.best) else self.best,
                "world_size": self.dist.world_size, "train_files": len(self.train_set)}

    def _resume(self, directory: Path) -> None:
        from safetensors.torch import load_file

        st = ck.load_training_state(directory, self.dist.rank)
        ts = st["trainer_state"]
        self.model.load_state_dict(load_file(str(directory / "model.safetensors")))
        self.optimizer.load_state_dict(st["optimizer"])
        self.step, self.position, self.total_steps = ts["step"], ts["position"], ts["total_steps"]
        self.best = math.inf if ts.get("best") is None else ts["best"]
        self.sampler.start = self.position
        self.last_checkpoint = directory
        if ts.get("train_files") != len(self.train_set):
            self.note(f"note: the training split had {ts.get('train_files')} files and now has {len(self.train_set)}; "
                      "the data order differs from the original run from here on")
        rng = st["rng"]
        if rng:
            torch.set_rng_state(rng["torch"])
            self.aug_gen.set_state(rng["aug"])
            self.sample_gen.set_state(rng["sample"])
            if "cuda" in rng and self.device.type == "cuda":
                torch.cuda.set_rng_state(rng["cuda"], self.device)
        else:
            self.note(f"note: {directory} has no random state for rank {self.dist.rank} (different number of "
                      "processes?); augmentation and sampling noise are reseeded")
            self.aug_gen.manual_seed(self.cfg.seed * 7919 + 101 + self.dist.rank + 7 * self.step)
            self.sample_gen.manual_seed(self.cfg.seed * 7919 + 202 + self.dist.rank + 7 * self.step)
        self.note(f"resuming {self.run_dir} from {directory.name} (step {self.step} of {self.total_steps})")

    def save_checkpoint(self) -> Path:
        """Write a resumable checkpoint of the current step (atomically); returns its directory."""
        final, tmp = ck.checkpoint_paths(self.run_dir, self.step)
        if final.exists():
            return final
        if self.dist.is_main:
            shutil.rmtree(tmp, ignore_errors=True)
            tmp.mkdir(parents=True)
        barrier(self.dist)
        ck.save_training_state(tmp, model=self.model, optimizer=self.optimizer, train_config=self.cfg.to_dict(),
                               trainer_state=self._trainer_state(), rng=self._rng_state(), rank=self.dist.rank,
                               write_shared=self.dist.is_main)
        barrier(self.dist)
        if self.dist.is_main:
            ck.publish_checkpoint(self.run_dir, tmp, final, self.step, self.cfg.keep_checkpoints)
            self.log.event("checkpoint", self.step, path=str(final))
        self.last_checkpoint = final
        return final

    # ------------------------------------------------------------------ one step
    def _autocast(self):
        if not self.amp:
            return nullcontext()
        return torch.autocast(device_type=self.device.type, dtype=torch.bfloat16)

    def train_step(self, radiance: torch.Tensor, depth: torch.Tensor, names: list[str]) -> dict:
        """One optimiser step on a batch (B, 3, H, W) / (B, 1, H, W); returns scalars."""
        cfg = self.cfg
        self.model.train()
        rad = radiance.to(self.device, non_blocking=True)
        dep = depth.to(self.device, non_blocking=True)
        rad, dep = augment_batch(rad, dep, self.aug_gen, roll=cfg.aug_roll, flip=cfg.aug_mirror,
                                 tilt_deg=cfg.aug_tilt_deg)
        norm = self.model.normalization
        x = norm.normalize(rad, dep)
        lr = learning_rate(self.step, self.total_steps, cfg.lr, cfg.min_lr, cfg.warmup_steps)
        for group in self.optimizer.param_groups:
            group["lr"] = lr
        with self._autocast():
            x_hat, post = self.ddp(x, True, self.sample_gen)
        terms = vae_loss(x_hat.float(), x, post.mean.float(), post.logvar.float(), self.step, norm,
                         target_radiance=rad, config=cfg.loss_config)
        total = terms["total"]
        self._check_finite(total, "loss", terms, names)
        self.optimizer.zero_grad(set_to_none=True)
        total.backward()
        clip = cfg.grad_clip if cfg.grad_clip > 0 else math.inf
        gnorm = torch.nn.utils.clip_grad_norm_(self.model.parameters(), clip)
        self._check_finite(gnorm, "gradient norm", terms, names)
        self.optimizer.step()
        values = torch.stack([terms[k].detach().float() for k in LOSS_TERMS] + [gnorm.detach().float()])
        values = all_reduce_mean(values, self.dist).tolist()  # one device sync per step
        out = dict(zip(LOSS_TERMS + ("grad_norm",), values))
        out["lr"] = lr
        return out

    def _check_finite(self, value: torch.Tensor, what: str, terms: dict, names: list[str]) -> None:
        bad = broadcast_flag(not bool(torch.isfinite(value).all()), self.dist)
        if not bad:
            return
        parts = {k: float(v.detach()) for k, v in terms.items() if k in LOSS_TERMS}
        last = str(self.last_checkpoint) if self.last_checkpoint else "none yet (no checkpoint was written)"
        msg = (f"non-finite {what} at step {self.step + 1} (epoch {self.sampler.epoch_of(self.position - 1)}); "
               f"loss terms {parts}; batch files: {', '.join(names)}; last good checkpoint: {last}. "
               "Check these files (roomlight data stats), lower --lr or raise the clipping, then rerun the same "
               "command to continue from the last checkpoint")
        self.log.event("stop", self.step + 1, reason=f"non-finite {what}", files=names, last_checkpoint=last)
        raise TrainingError(msg)

    # ------------------------------------------------------------------ evaluation and images
    @torch.no_grad()
    def validate(self) -> dict:
        """Mean loss terms, LDR PSNR and depth AbsRel of posterior-mean reconstructions.

        Uses the validation split (or, without one, the first training batches) in file order,
        without augmentation. Updates ``RUN/best`` when the total loss improves.
        """
        from roomlight.prior.eval.metrics import abs_rel, psnr, to_ldr
        from roomlight.core.render.variant import recheck_threads

        recheck_threads(note=self.note)  # a long run: other jobs may have started or ended since the last check
        ds = self.val_set if self.val_set is not None else self.train_set
        tag = "val" if self.val_set is not None else "val_on_train"
        bs = min(self.cfg.batch_size, len(ds))
        order = list(range(len(ds)))
        sums: dict[str, float] = {}
        count = 0
        self.model.eval()
        norm = self.model.normalization
        for start in range(0, min(len(ds), bs * self.cfg.val_batches), bs):
            batch = collate_panoramas([ds[i] for i in order[start:start + bs]])
            if batch["radiance"] is None:
                continue
            rad, dep = batch["radiance"].to(self.device), batch["depth"].to(self.device)
            x = norm.normalize(rad, dep)
            with self._autocast():
                x_hat, post = self.model(x, False)
            x_hat = x_hat.float()
            terms = vae_loss(x_hat, x, post.mean.float(), post.logvar.float(), self.step, norm,
                             target_radiance=rad, config=self.cfg.loss_config)
            rad_hat, dep_hat = norm.denormalize(x_hat)
            n = rad.shape[0]
            vals = {k: float(terms[k]) * n for k in LOSS_TERMS}
            vals["psnr_ldr"] = float(psnr(to_ldr(rad_hat, rad), to_ldr(rad)).clamp(max=100).sum())
            if getattr(self.model, "has_depth", True):  # VENI's reconstructions carry the input's depth
                vals["abs_rel"] = float(abs_rel(dep_hat, dep).sum())
            for k, v in vals.items():
                sums[k] = sums.get(k, 0.0) + v
            count += n
        self.model.train()
        if count == 0:
            return {}
        means = {k: v / count for k, v in sums.items()}
        self.log.event(tag, self.step, **means)
        self.log.scalars(tag, self.step, means)
        if means["total"] < self.best:
            self.best = means["total"]
            self._save_best(tag, means)
        return means

    def _save_best(self, tag: str, means: dict) -> None:
        tmp = self.run_dir / ".tmp-best"
        shutil.rmtree(tmp, ignore_errors=True)
        self.model.save_pretrained(tmp, training_config=self.cfg.to_dict())
        ck.atomic_write_text(tmp / "best.json", json.dumps({"step": self.step, "metric": f"{tag}/total",
                                                            **means}, indent=2) + "\n")
        ck.replace_dir(tmp, self.run_dir / "best")

    @torch.no_grad()
    def write_images(self, count: int = 4) -> Path | None:
        """Panel of validation inputs, their reconstructions and prior samples (fixed z) to RUN/images."""
        from roomlight.core.io import save_png
        from roomlight.prior.eval.panels import training_panel

        ds = self.val_set if self.val_set is not None else self.train_set
        batch = collate_panoramas([ds[i] for i in range(min(count, len(ds)))])
        if batch["radiance"] is None:
            return None
        self.model.eval()
        rad, dep = batch["radiance"].to(self.device), batch["depth"].to(self.device)
        x_hat, _ = self.model(self.model.normalization.normalize(rad, dep), False)
        recon = self.model.normalization.denormalize(x_hat.float())
        z = torch.randn(count, self.model.config.latent_dim, generator=torch.Generator().manual_seed(self.cfg.seed))
        samples = self.model.decode(z.to(self.device))
        if samples[1] is None:  # VENI: radiance only; its depth column shows a constant
            samples = (samples[0], torch.ones_like(samples[0][:, :1]))
        self.model.train()
        panel = training_panel((rad, dep), recon, samples)
        path = self.run_dir / "images" / f"{ck.checkpoint_name(self.step)}.png"
        path.parent.mkdir(exist_ok=True)
        save_png(path, panel)
        self.log.image("panels", self.step, panel)
        return path

    # ------------------------------------------------------------------ the loop
    def _report_skipped(self, skipped) -> None:
        """Each skipped file (name, reason) and repaired file (name, None, repair) once per run."""
        for name, why, *fix in skipped:
            if name not in self._reported:
                self._reported.add(name)
                self.note(f"note: {fix[0]}" if fix else f"skipping {name}: {why}")
                self.log.event("repaired" if fix else "skipped", self.step, file=name, reason=fix[0] if fix else why)

    def fit(self, until: int | None = None, time_budget_s: float | None = None) -> dict:
        """Train up to step ``until`` (default: the end of the schedule); returns a summary.

        ``time_budget_s`` stops earlier, after the first step that ends past that many seconds
        of wall time (validation, images and a checkpoint follow as at any stop): the way to
        give several recipes the same CPU budget, or to train in sittings. The schedule is not
        changed by it, so the run continues exactly when called again.

        Writes a checkpoint at the end, every ``ckpt_every`` steps, and on Ctrl-C or SIGTERM: the
        signal is held until the current step is complete, then that step is checkpointed and
        :class:`~roomlight.prior.train.interrupt.Interrupted` (a ``KeyboardInterrupt``) is raised, so
        re-running continues exactly as if nothing had happened.
        """
        from roomlight.core.progress import progress_bar

        cfg, main = self.cfg, self.dist.is_main
        stop = min(until or self.total_steps, self.total_steps)
        deadline = None if time_budget_s is None else time.perf_counter() + float(time_budget_s)
        if self.step >= stop:
            self.note(f"{self.run_dir}: already at step {self.step} of {self.total_steps}; nothing to do")
            return self.summary()
        self.sampler.start = self.position
        loader = DataLoader(self.train_set, batch_sampler=self.sampler, collate_fn=collate_panoramas,
                            num_workers=cfg.num_workers, pin_memory=self.device.type == "cuda")
        bar = progress_bar(total=stop, initial=self.step, desc="train", unit="step",
                           disable=not (main and cfg.progress))
        self.last_train: dict = {}
        it = iter(loader)
        with deferred_interrupts(self.note if main else None) as signalled:
            self._loop(it, stop, deadline, bar, signalled)
        return self.summary()

    def _loop(self, it, stop: int, deadline, bar, signalled) -> None:
        cfg, main = self.cfg, self.dist.is_main
        bpe = self.sampler.batches_per_epoch
        window, t0, seen = {}, time.perf_counter(), 0
        try:
            while self.step < stop:
                batch = next(it)
                self.position += 1
                self._report_skipped(batch["skipped"] + [(n, None, fix) for n, fix in batch.get("fixes", [])])
                if broadcast_flag(batch["radiance"] is None, self.dist):
                    continue
                out = self.train_step(batch["radiance"], batch["depth"], batch["names"])
                self.step += 1
                seen += len(batch["names"]) * self.dist.world_size
                for k, v in out.items():
                    window[k] = window.get(k, 0.0) + v
                window["n"] = window.get("n", 0) + 1
                bar.update(1)
                # Every rank must stop at the same step: one rank past the deadline stops all.
                if deadline is not None and broadcast_flag(time.perf_counter() >= deadline, self.dist):
                    stop = self.step
                if self.step % cfg.log_every == 0 or self.step == stop:
                    dt = time.perf_counter() - t0
                    means = {k: v / window["n"] for k, v in window.items() if k != "n"}
                    means["pano_per_s"] = seen / dt if dt > 0 else 0.0
                    self.last_train = means
                    self.log.event("train", self.step, epoch=self.sampler.epoch_of(self.position - 1), **means)
                    self.log.scalars("train", self.step, means)
                    bar.set_postfix(loss=f"{means['total']:.4f}", lr=f"{means['lr']:.2e}",
                                    pano_s=f"{means['pano_per_s']:.1f}")
                    window, t0, seen = {}, time.perf_counter(), 0
                epoch_end = self.position % bpe == 0
                if ((cfg.val_every and self.step % cfg.val_every == 0) or (not cfg.val_every and epoch_end)
                        or self.step == stop):
                    if main:
                        self.validate()
                    barrier(self.dist)
                if main and cfg.image_every and (self.step % cfg.image_every == 0 or self.step == stop):
                    self.write_images()
                if self.step % cfg.ckpt_every == 0 or self.step == stop:
                    self.save_checkpoint()
                if broadcast_flag(signalled.signum is not None, self.dist):
                    raise Interrupted(signalled.signum or 2)  # at a step boundary: the state is consistent
        except KeyboardInterrupt as exc:
            bar.close()
            checkpoint_interrupted(exc, self.save_checkpoint, self.note, self.step, self.last_checkpoint)
            raise
        finally:
            bar.close()
            del it

    def summary(self) -> dict:
        """Where the run stands: step, schedule length, last train losses, best validation loss, paths."""
        return {"step": self.step, "total_steps": self.total_steps, "train": getattr(self, "last_train", {}),
                "best": None if math.isinf(self.best) else self.best, "run_dir": str(self.run_dir),
                "last_checkpoint": str(self.last_checkpoint) if self.last_checkpoint else None}

    def close(self) -> None:
        self.log.close()
