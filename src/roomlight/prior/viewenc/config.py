"""Settings of a view-encoder training run (docs/photo.md, "The view encoder")."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

from roomlight.core.config import StrictConfig, checked_fields
from roomlight.errors import RoomlightError
from roomlight.prior.losses import LossConfig

__all__ = ["ViewTrainConfig", "RESUME_SAFE_FIELDS"]

#: Fields that may differ when a run is resumed (they do not change what is optimised).
RESUME_SAFE_FIELDS = ("max_steps", "val_every", "ckpt_every", "log_every", "keep_checkpoints", "progress")


@dataclass(frozen=True)
class ViewTrainConfig(StrictConfig):
    """Everything that defines a view-encoder training run."""

    #: Panoramas per optimiser step (one random view of each).
    batch_size: int = 32
    #: Optimiser steps of the cosine schedule.
    max_steps: int = 6000
    #: Peak learning rate (AdamW), reached after ``warmup_steps``.
    lr: float = 3e-4
    #: Learning rate at the end of the cosine decay.
    min_lr: float = 1e-5
    #: Steps of linear warm-up.
    warmup_steps: int = 100
    #: AdamW decoupled weight decay.
    weight_decay: float = 0.01
    #: Clip the global gradient norm to this value (<= 0: no clipping).
    grad_clip: float = 10.0
    #: Horizontal field of view of the training views, degrees (uniform).
    fov_deg: tuple[float, float] = (40.0, 100.0)
    #: Largest |pitch| of a training view, degrees.
    pitch_deg: float = 25.0
    #: Largest |roll| of a training view, degrees.
    roll_deg: float = 5.0
    #: Width / height of the training views (uniform).
    aspect: tuple[float, float] = (1.0, 1.8)
    #: Log-average luminance a training view is exposed to before clipping at 1 (uniform in log).
    exposure_key: tuple[float, float] = (0.04, 0.4)
    #: Most random ellipses (objects) hiding the room in a view.
    occluders: int = 3
    #: Mirror the panorama left-right with probability 1/2.
    mirror: bool = True
    #: Share of training views whose depth is withheld (the log-depth channel set to 0), so that the
    #: encoder also reads photographs without a depth map; 0 keeps every view's depth (and the random
    #: sequence of runs made before this setting existed). Validation then scores each view both ways.
    depth_dropout: float = 0.0
    #: Weights of the reconstruction of the whole panorama through the frozen decoder
    #: (the fields of :class:`roomlight.prior.losses.LossConfig`; the KL weight is unused).
    loss: dict = field(default_factory=lambda: LossConfig(peak=0.3, kl_beta=0.0).to_dict())
    #: Weight of the mean squared distance between z and the full panorama's encoder mean.
    latent_weight: float = 1.0
    #: Weight of the squared error of the log exposure s.
    exposure_weight: float = 0.1
    #: Weight of the log-L1 error of the decoded room's irradiance at the capture point, on surfaces
    #: facing 14 directions (:func:`roomlight.prior.losses.irradiance.irradiance_loss`): keeps the
    #: energy of the unseen part of the room, which per-pixel losses let a guess smear and dim.
    #: 0 (the bundled encoders') leaves it out of the objective; it is scored at validation either way.
    irradiance_weight: float = 0.0
    #: Compare that irradiance after scaling the decoded room so that the cells the view shows have
    #: the truth's log-average luminance, as a photo fit's exposure match does
    #: (:func:`roomlight.prior.losses.irradiance.seen_matched`): the term then asks for the unseen
    #: part's energy relative to the seen part, the only energy a photo fit's start passes on.
    irradiance_seen_matched: bool = False
    #: Weight of the squared error of the decoded room's display values against the truth's, both exposed
    #: at the truth's key (:func:`roomlight.prior.losses.display.display_loss`; validation's ``psnr_ldr`` is
    #: ``-10 log10`` of it per view): asks for the whole room as its tone-mapped image shows it, the
    #: unseen lamps' places included. 0 (the bundled encoder's) leaves it out; it is logged either way.
    display_weight: float = 0.0
    #: Validation views (one per validation room, fixed) and how often they are scored.
    val_views: int = 96
    val_every: int = 250
    #: Checkpoint every this many steps (and at every stop); newest ``keep_checkpoints`` kept.
    ckpt_every: int = 250
    keep_checkpoints: int = 2
    #: Average the training losses over this many steps per log line.
    log_every: int = 25
    #: Seed of the data order, the views and the validation set.
    seed: int = 0
    #: Show a progress bar.
    progress: bool = True

    def __post_init__(self):
        ok = (self.batch_size >= 1 and self.max_steps >= 1 and self.lr > 0 and 0 < self.fov_deg[0] <= self.fov_deg[1] < 170
              and 0 < self.exposure_key[0] <= self.exposure_key[1] and self.occluders >= 0 and self.val_views >= 1
              and 0.0 <= self.depth_dropout <= 1.0 and self.irradiance_weight >= 0.0 and self.display_weight >= 0.0)
        if not ok:
            raise RoomlightError(f"view-encoder training settings out of range: {self.to_dict()}")
        LossConfig.from_dict(self.loss)

    @property
    def loss_config(self) -> LossConfig:
        return LossConfig.from_dict(self.loss)

    def replace(self, **overrides) -> "ViewTrainConfig":
        """A copy with fields replaced (``loss`` entries merged into the current ones)."""
        if isinstance(overrides.get("loss"), dict):
            overrides["loss"] = {**self.loss, **overrides["loss"]}
        return dataclasses.replace(self, **checked_fields(type(self), overrides))
