"""Training the prior: configuration, schedule, resumable checkpoints, the loop.

- :class:`TrainConfig`, :func:`get_train_preset`   the recipe (presets default / small / tiny)
- :class:`Trainer`                                  ``Trainer(cfg, data, run).fit()``; resumes
- :func:`learning_rate`                             warm-up + cosine schedule
- :func:`resolve_run_model`                         ``--model RUN`` -> the model directory (from
  :mod:`roomlight.prior.model.runs`, re-exported)

See docs/training.md.
"""

from __future__ import annotations

from roomlight.prior.train.checkpoint import latest_checkpoint, load_run_model, resolve_run_model
from roomlight.prior.train.config import (RESUME_SAFE_FIELDS, TRAIN_PRESETS, TrainConfig, config_differences,
                                    get_train_preset)
from roomlight.prior.train.schedule import learning_rate
from roomlight.prior.train.trainer import Trainer, TrainingError

__all__ = ["TrainConfig", "TRAIN_PRESETS", "get_train_preset", "RESUME_SAFE_FIELDS", "config_differences",
           "Trainer", "TrainingError", "learning_rate", "latest_checkpoint", "resolve_run_model", "load_run_model"]
