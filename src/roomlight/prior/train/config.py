"""Training configuration of the prior (supp. "Training details"; docs/training.md).

One dataclass, saved as ``RUN/train_config.json`` and inside every checkpoint. The defaults are
the paper's recipe; presets ``default``, ``small`` and ``tiny`` pair with the model presets of
the same name. CLI flags override single fields.

Resuming checks the saved config against the new one: fields that change the optimisation
(everything except :data:`RESUME_SAFE_FIELDS`) must be equal, otherwise the run is refused with
the list of differing fields.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

from roomlight.core.config import StrictConfig, checked_fields
from roomlight.errors import RoomlightError
from roomlight.prior.losses import LossConfig
from roomlight.prior.model.config import ModelConfig
from roomlight.prior.model.families import model_preset
from roomlight.prior.model.veni import VeniConfig

__all__ = ["TrainConfig", "TRAIN_PRESETS", "get_train_preset", "RESUME_SAFE_FIELDS", "config_differences"]


@dataclass(frozen=True)
class TrainConfig(StrictConfig):
    """Everything that defines a training run of :class:`~roomlight.prior.model.PanoVAE`."""

    #: Model architecture preset name (``default`` = the paper's network, ``small``, ``tiny``).
    model: str = "default"
    #: Fields of the preset's :class:`~roomlight.prior.model.ModelConfig` to change, e.g.
    #: ``{"adagn": false}`` or ``{"latitude": false}`` (the ablations; ``--set model_overrides.adagn=false``).
    model_overrides: dict = field(default_factory=dict)
    #: Global batch size (summed over all DDP processes); the paper uses 32.
    batch_size: int = 32
    #: Passes over the training split; the schedule spans epochs x floor(N / batch) steps.
    epochs: int = 300
    #: When > 0, train exactly this many optimiser steps instead of ``epochs``.
    max_steps: int = 0
    #: Peak learning rate, reached at the end of the warm-up.
    lr: float = 2e-4
    #: Learning rate at the end of the cosine decay.
    min_lr: float = 1e-5
    #: Steps of linear warm-up from 0 to ``lr``.
    warmup_steps: int = 250
    #: AdamW (beta1, beta2).
    betas: tuple[float, float] = (0.9, 0.99)
    #: AdamW decoupled weight decay.
    weight_decay: float = 0.01
    #: Clip the global gradient norm to this value (<= 0 disables clipping).
    grad_clip: float = 10.0
    #: Loss weights and settings: the fields of :class:`roomlight.prior.losses.LossConfig`.
    loss: dict = field(default_factory=lambda: LossConfig().to_dict())
    #: Augmentation: uniform random azimuth roll by whole columns.
    aug_roll: bool = True
    #: Augmentation: horizontal mirror with probability 1/2.
    aug_mirror: bool = True
    #: Augmentation: maximum tilt in degrees (a true rotation of the sphere); 0 disables it.
    aug_tilt_deg: float = 7.0
    #: Exposure-calibrate each panorama to unit log-average luminance when loading.
    calibrate: bool = True
    #: Clamp negative radiance to 0 when loading (the count is reported); otherwise such files are skipped.
    clamp_negative: bool = False
    #: Replace NaN/inf radiance by this value when loading (reported); None skips such files.
    fill_nonfinite: float | None = None
    #: Depth units fed to the network: ``metres`` (as stored) or ``scale-free`` (geometric mean 1).
    depth_units: str = "metres"
    #: Share of files held out for validation when the data folder has no train/ val/ folders.
    val_fraction: float = 0.05
    #: Seed of weights, data order, augmentation and posterior sampling.
    seed: int = 0
    #: Read panoramas from a packed float16/float32 cache built once (see roomlight.prior.data.cache).
    cache: bool = True
    #: Precision of the packed cache: ``float16`` or ``float32``.
    cache_dtype: str = "float16"
    #: Mixed precision: ``auto`` (bf16 autocast when CUDA is used), ``bf16`` or ``off``.
    amp: str = "auto"
    #: ``torch.compile`` the encoder and decoder: ``auto`` (only on CUDA), ``on`` or ``off``.
    compile: str = "auto"
    #: Data-loader worker processes (per DDP process).
    num_workers: int = 2
    #: Write scalars to the log / progress bar every this many steps.
    log_every: int = 10
    #: Validate (and update the best checkpoint) every this many steps; 0 = once per epoch.
    val_every: int = 0
    #: At most this many validation batches per validation.
    val_batches: int = 16
    #: Write a resumable checkpoint every this many steps (and at the end / on interrupt).
    ckpt_every: int = 1000
    #: Periodic checkpoints to keep (older ones are deleted).
    keep_checkpoints: int = 3
    #: Write image panels (inputs, reconstructions, samples) every this many steps; 0 = never.
    image_every: int = 1000
    #: Show a tqdm progress bar.
    progress: bool = True
    #: Start from the weights of this model (a model folder or a training run) instead of a random
    #: initialisation: fine-tuning, or a second schedule after a finished one. The architecture
    #: must match :attr:`model`, and the run adopts that model's normalisation statistics (the
    #: weights mean nothing under other ones). The optimiser and schedule start afresh.
    init_from: str | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "betas", tuple(float(b) for b in self.betas))
        object.__setattr__(self, "loss", dict(self.loss))
        object.__setattr__(self, "model_overrides", dict(self.model_overrides))
        if self.init_from is not None:  # one spelling per folder, so a resume given a relative path matches
            from pathlib import Path

            object.__setattr__(self, "init_from", str(Path(self.init_from).expanduser().resolve()))
        self.validate()

    def validate(self) -> None:
        """Raise :class:`RoomlightError` naming the first invalid field."""
        def bad(name: str, why: str):
            return RoomlightError(f"TrainConfig.{name} = {getattr(self, name)!r}: {why}")

        model_preset(self.model)  # raises for unknown presets
        self.model_config  # unknown or mistyped model_overrides are refused with the field's name
        for name in ("batch_size", "log_every", "ckpt_every", "val_batches", "keep_checkpoints"):
            if getattr(self, name) <= 0:
                raise bad(name, "must be positive")
        for name in ("epochs", "max_steps", "warmup_steps", "num_workers", "val_every", "image_every"):
            if getattr(self, name) < 0:
                raise bad(name, "must be >= 0")
        if self.epochs == 0 and self.max_steps == 0:
            raise bad("epochs", "epochs or max_steps must be positive")
        if not (self.lr > 0 and 0 <= self.min_lr <= self.lr):
            raise bad("min_lr", f"need 0 <= min_lr <= lr and lr > 0 (lr = {self.lr})")
        if not 0.0 <= self.val_fraction < 1.0:
            raise bad("val_fraction", "must be in [0, 1)")
        if self.depth_units not in ("metres", "scale-free"):
            raise bad("depth_units", "use 'metres' or 'scale-free'")
        if self.cache_dtype not in ("float16", "float32"):
            raise bad("cache_dtype", "use 'float16' or 'float32'")
        if self.amp not in ("auto", "bf16", "off"):
            raise bad("amp", "use 'auto', 'bf16' or 'off'")
        if self.compile not in ("auto", "on", "off"):
            raise bad("compile", "use 'auto', 'on' or 'off'")
        if self.fill_nonfinite is not None and not math.isfinite(self.fill_nonfinite):
            raise bad("fill_nonfinite", "must be a finite number or None")
        if not 0.0 <= self.aug_tilt_deg <= 90.0:
            raise bad("aug_tilt_deg", "must be in [0, 90] degrees")
        LossConfig.from_dict(self.loss, where="TrainConfig.loss")  # names the entry and its type

    # ------------------------------------------------------------------ derived
    @property
    def model_config(self) -> ModelConfig | VeniConfig:
        """The architecture of the preset named by :attr:`model` (a PanoVAE or a VENI preset), with
        :attr:`model_overrides` applied."""
        try:
            return model_preset(self.model).override(**self.model_overrides)
        except RoomlightError as exc:
            raise RoomlightError(f"TrainConfig.model_overrides: {exc}") from None

    @property
    def loss_config(self) -> LossConfig:
        """:attr:`loss` as a :class:`~roomlight.prior.losses.LossConfig`."""
        return LossConfig.from_dict(self.loss)

    # ------------------------------------------------------------------ (de)serialisation
    # to_dict / from_dict come from StrictConfig: unknown fields and wrong types are refused with
    # the field's path and, for a misspelt name, the closest valid one.

    def replace(self, **overrides) -> "TrainConfig":
        """A copy with some fields replaced (``loss`` and ``model_overrides`` entries may be given as
        ``loss={...}``, merged into the current ones)."""
        for name in ("loss", "model_overrides"):
            if isinstance(overrides.get(name), dict):
                overrides[name] = {**getattr(self, name), **overrides[name]}
        return dataclasses.replace(self, **checked_fields(type(self), overrides))

    override = replace


#: Fields that may differ when a run is resumed: they change logging, speed or book-keeping, not
#: the sequence of optimiser updates.
RESUME_SAFE_FIELDS = frozenset({
    "num_workers", "log_every", "val_every", "val_batches", "ckpt_every", "keep_checkpoints",
    "image_every", "progress", "compile",
})

#: Named configurations paired with the model presets. ``default`` is the paper's recipe;
#: ``small`` and ``compact`` train the 64 x 128 and 32 x 64 models with the same recipe; ``tiny`` is for tests and smoke runs
#: (16 x 32 model, batch 4, higher learning rate, short warm-ups, frequent checkpoints, no worker
#: processes, 3 gradient-loss octaves since a 4th would be only 2 x 4 pixels).
TRAIN_PRESETS: dict[str, TrainConfig] = {
    "default": TrainConfig(),
    "small": TrainConfig(model="small", image_every=500, ckpt_every=500),
    "compact": TrainConfig(model="compact", image_every=500, ckpt_every=500),
    "lite": TrainConfig(model="lite", image_every=500, ckpt_every=250),
    "tiny": TrainConfig(
        model="tiny", batch_size=4, epochs=100, lr=2e-3, min_lr=1e-4, warmup_steps=10,
        loss={**LossConfig().to_dict(), "kl_warmup_steps": 100, "grad_levels": 3},
        num_workers=0, log_every=5, val_every=50, val_batches=4, ckpt_every=50, image_every=0,
    ),
}
# VENI and VENI+D train with the lite prior's recipe and objective (the comparison is of architectures);
# VENI's objective has no depth terms, since its reconstructions carry the input's depth through.
for _name in ("veni", "veni-d"):
    TRAIN_PRESETS[_name] = dataclasses.replace(TRAIN_PRESETS["lite"], model=_name)
    TRAIN_PRESETS[f"{_name}-tiny"] = dataclasses.replace(TRAIN_PRESETS["tiny"], model=f"{_name}-tiny")


def get_train_preset(name: str) -> TrainConfig:
    """The training preset called ``name`` (``default``, ``small``, ``compact`` or ``tiny``)."""
    try:
        return TRAIN_PRESETS[name]
    except KeyError:
        raise RoomlightError(f"unknown training preset {name!r}; choose one of {sorted(TRAIN_PRESETS)}") from None


def config_differences(saved: TrainConfig, new: TrainConfig, ignore=RESUME_SAFE_FIELDS) -> list[str]:
    """``field: saved -> new`` for every differing field not in ``ignore`` (loss entries listed as ``loss.X``)."""
    diffs = []
    a, b = saved.to_dict(), new.to_dict()
    for k in a:
        if k in ignore or a[k] == b[k]:
            continue
        if k in ("loss", "model_overrides"):
            for lk in sorted(set(a[k]) | set(b[k])):
                if a[k].get(lk) != b[k].get(lk):
                    diffs.append(f"{k}.{lk}: {a[k].get(lk)!r} -> {b[k].get(lk)!r}")
        else:
            diffs.append(f"{k}: {a[k]!r} -> {b[k]!r}")
    return diffs
