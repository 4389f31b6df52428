"""Run folders: from ``--model PATH`` to a model, and the authors' checkpoint converted once.

A training run (``roomlight train --out RUN``) holds ``RUN/best/`` (the best model by validation
loss) and ``RUN/checkpoints/step-NNNNNNNN/`` (resumable checkpoints, see
:mod:`roomlight.prior.train.checkpoint`, which writes them). Every command that takes ``--model``
resolves it here, so inference code never imports the training package.
"""

from __future__ import annotations

import json
from pathlib import Path

import torch

from roomlight.errors import InputFileError
from roomlight.prior.model.convert import load_authors_run
from roomlight.prior.model.panovae import PanoVAE

__all__ = ["STATE_NAME", "OPTIMIZER_NAME", "latest_checkpoint", "resolve_run_model", "load_run_model",
           "convert_authors_checkpoint"]

#: Written last into a checkpoint directory: its presence marks the checkpoint complete.
STATE_NAME = "trainer_state.json"
OPTIMIZER_NAME = "optimizer.safetensors"


def _complete(d: Path) -> bool:
    return d.is_dir() and (d / STATE_NAME).exists() and (d / OPTIMIZER_NAME).exists()


def latest_checkpoint(run_dir: str | Path) -> Path | None:
    """The newest complete checkpoint directory of a run, or None."""
    ckdir = Path(run_dir) / "checkpoints"
    if not ckdir.is_dir():
        return None
    pointer = ckdir / "latest.json"
    if pointer.exists():
        try:
            d = ckdir / json.loads(pointer.read_text())["name"]
            newest = max((p for p in ckdir.glob("step-*") if _complete(p)), default=None)
            if _complete(d) and (newest is None or newest.name <= d.name):
                return d
        except (OSError, KeyError, json.JSONDecodeError):
            pass
    return max((p for p in ckdir.glob("step-*") if _complete(p)), default=None)


def resolve_run_model(path: str | Path) -> Path:
    """Directory to load for ``--model PATH``.

    ``PATH`` may be a model directory itself (``config.json`` + ``model.safetensors``, or the
    authors' run folder), a training run (then ``RUN/best``, else its newest checkpoint), or, when
    no such path exists, the name of a bundled model (:mod:`roomlight.prior.model.bundled`).
    """
    p = Path(path)
    if not p.exists():
        from roomlight.prior.model.bundled import BUNDLED_MODELS, bundled_model_path

        if str(path) in BUNDLED_MODELS:
            bundled = bundled_model_path(str(path))
            if bundled is None:
                raise InputFileError(p, f"the bundled model {str(path)!r} is not part of this installation",
                                     "pass a model directory or a training run")
            return bundled
        raise InputFileError(p, "no such file or directory",
                             f"pass a model directory, a training run or a bundled model ({', '.join(BUNDLED_MODELS)})")
    if p.is_file() or (p / "model.safetensors").exists() or (p / "config.yaml").exists():
        return p
    for cand in (p / "best", p / "best.old"):
        if (cand / "model.safetensors").exists():
            return cand
    latest = latest_checkpoint(p)
    if latest is not None:
        return latest
    raise InputFileError(p, "holds no model: expected config.json + model.safetensors, a best/ folder "
                         "or checkpoints/step-*", "train one with `roomlight train` or convert one with "
                         "`roomlight convert`")


def load_run_model(path: str | Path, device: str | None = None):
    """The model at ``resolve_run_model(path)`` (a PanoVAE, or VENI / VENI+D by its config.json) on
    ``device`` (default: CUDA if available)."""
    from roomlight.prior.model.families import load_model

    if device is None:
        device = "cuda" if torch.cuda.is_available() else "cpu"
    return load_model(resolve_run_model(path), device=device)


def convert_authors_checkpoint(run_dir: str | Path, out_dir: str | Path) -> Path:
    """Convert the authors' run folder into a roomlight checkpoint (safetensors + config.json).

    The authors' normalisation and ``depth_units = "scale-free"`` are recorded in the output, so
    the converted model behaves exactly like the original. Returns ``out_dir``.
    """
    model = load_authors_run(run_dir, PanoVAE)  # warns that the input is a third-party pickle
    training = model.metadata.pop("training", None)
    return model.save_pretrained(out_dir, training_config=training)
