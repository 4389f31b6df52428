"""Training the view encoder against a frozen prior (docs/photo.md, "The view encoder").

Each step draws ``batch_size`` training panoramas, cuts one random view of each
(:func:`~roomlight.prior.viewenc.views.training_view`), and minimises

    L = L_rec(decode(z), X) + latent_weight · mean_d (z_d - mu_d(X))^2 + exposure_weight · (s - s*)^2
        + irradiance_weight · L_irr(decode(z), X) + display_weight · L_display(decode(z), X)

where X is the whole (z-scored) panorama, L_rec the prior's reconstruction losses (L1, Scharr
gradients, peak; :func:`roomlight.prior.losses.vae_loss` without its KL term) through the frozen
decoder, mu(X) the prior encoder's posterior mean of the whole panorama, and L_irr the log-L1 error
of the irradiance at the capture point (:mod:`roomlight.prior.losses.irradiance`; weight 0 by
default), with ``irradiance_seen_matched`` taken after the decoded room is scaled to the truth's
level on the cells the view shows, and L_display the squared error of the two rooms' display values
(:mod:`roomlight.prior.losses.display`: what validation's ``psnr_ldr`` scores; weight 0 by default).
The prior's weights never change; only the view encoder learns.
Validation also reports ``irradiance_stops``, the decoded room's mean log2 irradiance ratio to the
truth's (negative: the guess is too dim), and ``irradiance_seen_stops``, the same after that scaling:
the energy bias a photo fit starts with.

Run folder::

    RUN/run.json                 the settings, the prior (path and weights checksum), the data folder
    RUN/log.jsonl                one JSON object per event (train, val, reference, checkpoint)
    RUN/checkpoints/step-N/      view encoder + optimiser + trainer_state.json (with the data RNG)
    RUN/best/                    the view encoder with the lowest validation loss

Running the same command again continues from the newest checkpoint exactly: the data order and
every view come from one NumPy generator whose state is saved with each checkpoint.
"""

from __future__ import annotations

import json
import math
import shutil
import time
from pathlib import Path

import numpy as np
import torch

from roomlight.errors import RoomlightError
from roomlight.prior.losses import vae_loss
from roomlight.prior.losses.display import display_loss
from roomlight.prior.losses.irradiance import irradiance_log_ratio, irradiance_loss
from roomlight.prior.model.view_encoder import SEEN_CHANNEL, ViewEncoder
from roomlight.prior.train import checkpoint as ck
from roomlight.prior.train.config import config_differences
from roomlight.prior.train.interrupt import Interrupted, checkpoint_interrupted, deferred_interrupts
from roomlight.prior.train.schedule import learning_rate
from roomlight.prior.viewenc.config import RESUME_SAFE_FIELDS, ViewTrainConfig
from roomlight.prior.viewenc.views import training_view

__all__ = ["ViewEncoderTrainer", "load_panoramas", "TERMS"]

#: The validation scores logged for the two reference starts (z = 0, the whole panorama's encoder mean).
REFERENCE_SCORES = ("total", "psnr_ldr", "abs_rel", "irradiance_stops", "irradiance_seen_stops")

TERMS = ("total", "l1_radiance", "l1_depth", "grad_radiance", "grad_depth", "peak", "latent", "exposure", "irradiance",
         "display")


def load_panoramas(data_dir, split: str, resolution, limit: int | None = None, note=print
                   ) -> tuple[torch.Tensor, torch.Tensor, list[str]]:
    """Every usable panorama of ``data_dir``'s ``split`` at ``resolution``, in memory.

    Returns radiance (N, 3, H, W) calibrated, depth (N, 1, H, W) metres and the file names; the
    packed cache of ``roomlight train`` is used (and built) when it can be.
    """
    from roomlight.prior.data import PackedCache, PanoramaDataset, collate_panoramas, split_files
    from roomlight.prior.data.cache import default_cache_path

    files = split_files(Path(data_dir), 0.05)[split]
    if limit:
        files = files[:limit]
    if not files:
        raise RoomlightError(f"{data_dir}: no panoramas in the {split} split")
    cache = None
    try:
        path = default_cache_path(data_dir, resolution, "float16", True, "metres").with_name(
            f"pack-{resolution[0]}x{resolution[1]}-{split}-{len(files)}.npy")
        cache = PackedCache.open_or_build(data_dir, files, resolution, path=path, dtype="float16", calibrate=True,
                                          depth_units="metres", progress=True, log=note)
    except OSError:  # a read-only data folder: decode the files directly
        cache = None
    ds = PanoramaDataset(files, resolution, root=data_dir, cache=cache)
    rads, deps, names = [], [], []
    for start in range(0, len(ds), 64):
        batch = collate_panoramas([ds[i] for i in range(start, min(start + 64, len(ds)))])
        for name, why in batch["skipped"]:
            note(f"skipping {name}: {why}")
        if batch["radiance"] is not None:
            rads.append(batch["radiance"])
            deps.append(batch["depth"])
            names.extend(batch["names"])
    if not rads:
        raise RoomlightError(f"{data_dir}: no usable panorama in the {split} split")
    return torch.cat(rads), torch.cat(deps), names


def _seen_cells(x: torch.Tensor) -> torch.Tensor:
    """(B, H, W) bool: the cells the views (B, 5, H, W) show (the input's seen channel)."""
    return x[:, SEEN_CHANNEL] > 0.5


class ViewEncoderTrainer:
    """Trains a :class:`ViewEncoder` for ``prior`` (see the module docstring).

    Args:
        config: the run's settings.
        prior: the frozen :class:`~roomlight.prior.model.PanoVAE` (its ``source_path`` is recorded).
        data_dir: panorama folder with ``train/`` and ``val/`` (``roomlight synth`` writes them).
        run_dir: output folder; with checkpoints in it the run continues.
        prior_path: where the prior was loaded from (recorded in ``run.json``).
    """

    def __init__(self, config: ViewTrainConfig, prior, data_dir, run_dir, prior_path=None, note=None,
                 limit: int | None = None):
        from roomlight.prior.model.weights import file_sha256

        self.cfg, self.prior = config, prior.eval()
        for p in self.prior.parameters():
            p.requires_grad_(False)
        self.note = note or print
        self.run_dir = Path(run_dir)
        # the checksum loading verified, else (weights saved before checksums) the file's: a training run
        # stands for its best/ model, so the file is the one resolve_run_model loaded
        self.prior_sha = getattr(prior, "_weights_sha256", None)
        if self.prior_sha is None and prior_path is not None:
            from roomlight.prior.model.runs import resolve_run_model

            weights = resolve_run_model(prior_path) / "model.safetensors"
            if weights.exists():
                self.prior_sha = file_sha256(weights)
        fresh = self._check_run(prior_path, data_dir)
        res = prior.config.resolution
        # The data first: a folder without usable panoramas stops the run before anything is written.
        self.train_rad, self.train_dep, self.train_names = load_panoramas(data_dir, "train", res, limit, self.note)
        val_rad, val_dep, _ = load_panoramas(data_dir, "val", res, config.val_views, self.note)
        self.run_dir.mkdir(parents=True, exist_ok=True)
        self.targets = self._encoder_means(self.train_rad, self.train_dep)
        self.val = self._validation_views(val_rad, val_dep)
        torch.manual_seed(config.seed)
        self.net = ViewEncoder.from_prior(prior)
        self.net.prior_sha256 = self.prior_sha
        self.optimizer = torch.optim.AdamW(self.net.parameters(), lr=config.lr, betas=(0.9, 0.99),
                                           weight_decay=config.weight_decay)
        self.rng = np.random.default_rng(config.seed)
        self.step, self.best = 0, math.inf
        self.last_checkpoint = None
        latest = ck.latest_checkpoint(self.run_dir)
        if latest is not None:
            self._resume(latest)
        if fresh:
            ck.atomic_write_text(self.run_dir / "run.json", json.dumps(
                {"config": config.to_dict(), "prior": None if prior_path is None else str(Path(prior_path).resolve()),
                 "prior_weights_sha256": self.prior_sha, "data": str(Path(data_dir).resolve()),
                 "train_panoramas": len(self.train_names)}, indent=2) + "\n")
            self._log("reference", 0, **self.reference_scores())

    # ------------------------------------------------------------------ setup
    def _check_run(self, prior_path, data_dir) -> bool:
        path = self.run_dir / "run.json"
        if not path.exists():
            return True
        saved = json.loads(path.read_text())
        diffs = config_differences(ViewTrainConfig.from_dict(saved["config"]), self.cfg, RESUME_SAFE_FIELDS)
        if saved.get("prior_weights_sha256") != self.prior_sha:
            diffs.append("the prior's weights")
        if diffs:
            raise RoomlightError(f"{self.run_dir}: cannot resume, the run was started with other settings "
                                 f"({'; '.join(diffs)}); rerun with the original ones or pass a new --out")
        return False

    @torch.no_grad()
    def _encoder_means(self, rad: torch.Tensor, dep: torch.Tensor) -> torch.Tensor:
        """(N, 2, D): the prior encoder's posterior means of each panorama, as is and mirrored."""
        out = []
        for flip in (False, True):
            means = []
            for i in range(0, len(rad), 32):
                r, d = rad[i:i + 32], dep[i:i + 32]
                if flip:
                    r, d = r.flip(-1), d.flip(-1)
                means.append(self.prior.encode(r, d).mean)
            out.append(torch.cat(means))
        return torch.stack(out, dim=1)

    def _validation_views(self, rad, dep) -> dict:
        rng = np.random.default_rng(10_000 + self.cfg.seed)
        # every validation view keeps its depth; with depth_dropout the same views are also scored without it
        views = [training_view(rad[i], dep[i], rng, self.cfg, self.prior.normalization, withhold=False)
                 for i in range(len(rad))]
        rad = torch.stack([r.flip(-1) if v.mirrored else r for r, v in zip(rad, views)])
        dep = torch.stack([d.flip(-1) if v.mirrored else d for d, v in zip(dep, views)])
        with torch.no_grad():
            mu = self.prior.encode(rad, dep).mean
        return {"x": torch.stack([v.x for v in views]), "s": torch.tensor([v.exposure_target for v in views]),
                "radiance": rad, "depth": dep, "mean": mu,
                "seen": float(np.mean([v.seen_fraction for v in views]))}

    # ------------------------------------------------------------------ objective
    def losses(self, z, s, radiance, depth, mean, s_target, seen) -> dict:
        """Every term (module docstring) for a batch; ``total`` is the weighted sum.

        ``seen``: (B, H, W) the cells each view shows (the input's seen channel)."""
        norm = self.prior.normalization
        x = norm.normalize(radiance, depth)
        x_hat = self.prior.decode_normalized(z)
        t = vae_loss(x_hat, x, z, torch.zeros_like(z), 0, norm, target_radiance=radiance,
                     config=self.cfg.loss_config)
        t = {k: t[k] for k in TERMS if k in t}
        t["latent"] = (z - mean).square().mean()
        t["exposure"] = (s - s_target).square().mean()
        rad_hat = norm.denormalize(x_hat)[0]
        t["irradiance"] = irradiance_loss(rad_hat, radiance, seen=seen if self.cfg.irradiance_seen_matched else None)
        t["display"] = display_loss(rad_hat, radiance)
        t["total"] = t["total"] + self.cfg.latent_weight * t["latent"] + self.cfg.exposure_weight * t["exposure"]
        if self.cfg.irradiance_weight > 0:
            t["total"] = t["total"] + self.cfg.irradiance_weight * t["irradiance"]
        if self.cfg.display_weight > 0:
            t["total"] = t["total"] + self.cfg.display_weight * t["display"]
        return t

    def train_step(self) -> dict:
        cfg = self.cfg
        idx = self.rng.integers(0, len(self.train_rad), cfg.batch_size)
        views = [training_view(self.train_rad[i], self.train_dep[i], self.rng, cfg, self.prior.normalization)
                 for i in idx]
        flips = torch.tensor([v.mirrored for v in views])
        rad = torch.where(flips[:, None, None, None], self.train_rad[idx].flip(-1), self.train_rad[idx])
        dep = torch.where(flips[:, None, None, None], self.train_dep[idx].flip(-1), self.train_dep[idx])
        mean = self.targets[torch.as_tensor(idx), flips.long()]
        x = torch.stack([v.x for v in views])
        s_target = torch.tensor([v.exposure_target for v in views])
        lr = learning_rate(self.step, cfg.max_steps, cfg.lr, cfg.min_lr, cfg.warmup_steps)
        for g in self.optimizer.param_groups:
            g["lr"] = lr
        self.net.train()
        z, s = self.net(x)
        terms = self.losses(z, s, rad, dep, mean, s_target, _seen_cells(x))
        if not bool(torch.isfinite(terms["total"])):
            raise RoomlightError(f"non-finite view-encoder loss at step {self.step + 1} "
                                 f"({ {k: float(v) for k, v in terms.items()} }); rerun to continue from "
                                 f"{self.last_checkpoint}, with a lower --lr")
        self.optimizer.zero_grad(set_to_none=True)
        terms["total"].backward()
        gnorm = torch.nn.utils.clip_grad_norm_(self.net.parameters(), cfg.grad_clip if cfg.grad_clip > 0 else math.inf)
        self.optimizer.step()
        out = {k: float(v.detach()) for k, v in terms.items()}
        out.update(grad_norm=float(gnorm), lr=lr)
        return out

    # ------------------------------------------------------------------ evaluation
    @torch.no_grad()
    def _scores(self, z, s) -> dict:
        from roomlight.prior.eval.metrics import abs_rel, psnr, to_ldr

        v = self.val
        seen = _seen_cells(v["x"])
        terms = self.losses(z, s, v["radiance"], v["depth"], v["mean"], v["s"], seen)
        rad_hat, dep_hat = self.prior.decode(z)
        out = {k: float(t) for k, t in terms.items()}
        out["psnr_ldr"] = float(psnr(to_ldr(rad_hat, v["radiance"]), to_ldr(v["radiance"])).clamp(max=100).mean())
        out["abs_rel"] = float(abs_rel(dep_hat, v["depth"]).mean())
        out["irradiance_stops"] = float(irradiance_log_ratio(rad_hat, v["radiance"]).mean())
        out["irradiance_seen_stops"] = float(irradiance_log_ratio(rad_hat, v["radiance"], seen=seen).mean())
        return out

    @torch.no_grad()
    def validate(self) -> dict:
        """Scores of the fixed validation views (loss terms, LDR PSNR, depth AbsRel); keeps the best.

        With ``depth_dropout`` > 0 the views are scored a second time with their depth withheld
        (``nodepth_*``), and the best is the lowest mean of the two totals (``selection``)."""
        from roomlight.prior.model.view_encoder import withhold_depth

        self.net.eval()
        z, s = self.net(self.val["x"])
        scores = self._scores(z, s)
        selection = scores["total"]
        if self.cfg.depth_dropout > 0:
            z, s = self.net(withhold_depth(self.val["x"]))
            scores.update({f"nodepth_{k}": v for k, v in self._scores(z, s).items()})
            selection = 0.5 * (scores["total"] + scores["nodepth_total"])
            scores["selection"] = selection
        self._log("val", self.step, **scores)
        if selection < self.best:
            self.best = selection
            tmp = self.run_dir / ".tmp-best"
            shutil.rmtree(tmp, ignore_errors=True)
            self.net.save_pretrained(tmp, training_config=self.cfg.to_dict())
            ck.atomic_write_text(tmp / "best.json", json.dumps({"step": self.step, **scores}, indent=2) + "\n")
            ck.replace_dir(tmp, self.run_dir / "best")
        return scores

    @torch.no_grad()
    def reference_scores(self) -> dict:
        """The validation scores of two fixed starts, for scale: z = 0 (the prior's mean room) and
        the encoder mean of the *whole* panorama (what a view can at best reach)."""
        v = self.val
        zero = self._scores(torch.zeros_like(v["mean"]), v["s"])
        full = self._scores(v["mean"], v["s"])
        out = {f"zero_{k}": val for k, val in zero.items() if k in REFERENCE_SCORES}
        out.update({f"full_{k}": val for k, val in full.items() if k in REFERENCE_SCORES})
        out["seen_fraction"] = v["seen"]
        return out

    # ------------------------------------------------------------------ state
    def _log(self, kind: str, step: int, **values) -> None:
        with open(self.run_dir / "log.jsonl", "a") as f:
            f.write(json.dumps({"event": kind, "step": step, "time": time.time(), **values}) + "\n")

    def save_checkpoint(self) -> Path:
        final, tmp = ck.checkpoint_paths(self.run_dir, self.step)
        if final.exists():
            return final
        shutil.rmtree(tmp, ignore_errors=True)
        tmp.mkdir(parents=True)
        state = {"step": self.step, "best": None if math.isinf(self.best) else self.best,
                 "rng": self.rng.bit_generator.state}
        ck.save_training_state(tmp, model=self.net, optimizer=self.optimizer, train_config=self.cfg.to_dict(),
                               trainer_state=state, rng={"torch": torch.get_rng_state()})
        ck.publish_checkpoint(self.run_dir, tmp, final, self.step, self.cfg.keep_checkpoints)
        self._log("checkpoint", self.step, path=str(final))
        self.last_checkpoint = final
        return final

    def _resume(self, directory: Path) -> None:
        from safetensors.torch import load_file

        st = ck.load_training_state(directory)
        ts = st["trainer_state"]
        self.net.load_state_dict(load_file(str(directory / "model.safetensors")))
        self.optimizer.load_state_dict(st["optimizer"])
        self.step = int(ts["step"])
        self.best = math.inf if ts.get("best") is None else float(ts["best"])
        self.rng.bit_generator.state = ts["rng"]
        if "torch" in st["rng"]:
            torch.set_rng_state(st["rng"]["torch"])
        self.last_checkpoint = directory
        self.note(f"resuming {self.run_dir} from {directory.name} (step {self.step} of {self.cfg.max_steps})")

    # ------------------------------------------------------------------ the loop
    def fit(self, time_budget_s: float | None = None, until: int | None = None) -> dict:
        """Train to ``until`` (default: ``max_steps``) or until ``time_budget_s`` seconds have passed;
        a checkpoint is written at every stop, including Ctrl-C / SIGTERM after the current step."""
        from roomlight.core.progress import progress_bar

        cfg = self.cfg
        stop = min(until or cfg.max_steps, cfg.max_steps)
        deadline = None if time_budget_s is None else time.perf_counter() + time_budget_s
        if self.step >= stop:
            self.note(f"{self.run_dir}: already at step {self.step} of {cfg.max_steps}; nothing to do")
            return self.summary()
        bar = progress_bar(total=stop, initial=self.step, desc="train-view-encoder", unit="step",
                           disable=not cfg.progress)
        window: dict = {}
        t0 = time.perf_counter()
        with deferred_interrupts(self.note) as signalled:
            try:
                while self.step < stop:
                    out = self.train_step()
                    self.step += 1
                    bar.update(1)
                    for k, v in out.items():
                        window[k] = window.get(k, 0.0) + v
                    window["n"] = window.get("n", 0) + 1
                    if deadline is not None and time.perf_counter() >= deadline:
                        stop = self.step
                    if self.step % cfg.log_every == 0 or self.step == stop:
                        n = window.pop("n")
                        means = {k: v / n for k, v in window.items()}
                        means["views_per_s"] = n * cfg.batch_size / max(time.perf_counter() - t0, 1e-9)
                        self._log("train", self.step, **means)
                        bar.set_postfix(loss=f"{means['total']:.4f}", lr=f"{means['lr']:.1e}")
                        window, t0 = {}, time.perf_counter()
                    if self.step % cfg.val_every == 0 or self.step == stop:
                        self.validate()
                    if self.step % cfg.ckpt_every == 0 or self.step == stop:
                        self.save_checkpoint()
                    if signalled.signum is not None:
                        raise Interrupted(signalled.signum)
            except KeyboardInterrupt as exc:
                bar.close()
                checkpoint_interrupted(exc, self.save_checkpoint, self.note, self.step, self.last_checkpoint)
                raise
            finally:
                bar.close()
        return self.summary()

    def summary(self) -> dict:
        return {"step": self.step, "max_steps": self.cfg.max_steps, "best": None if math.isinf(self.best) else self.best,
                "run_dir": str(self.run_dir), "last_checkpoint": str(self.last_checkpoint) if self.last_checkpoint else None}
