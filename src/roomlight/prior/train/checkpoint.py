"""Resumable training checkpoints, without pickle, written atomically.

A checkpoint is a directory ``RUN/checkpoints/step-00001000/`` holding

- ``model.safetensors`` + ``config.json``: the model, loadable with ``PanoVAE.from_pretrained``;
- ``optimizer.safetensors``: AdamW moments per parameter, with the param groups as JSON metadata;
- ``rng-rank{r}.safetensors``: every random generator's state of DDP process r;
- ``trainer_state.json``: step, batches drawn, epoch, schedule length, best metric, written last.

It is assembled in a hidden temporary directory and renamed into place with ``os.replace``, a
single atomic operation, so a kill during a save leaves either the complete new checkpoint or
none. ``RUN/checkpoints/latest.json`` (also replaced atomically) names the newest one; if it is
missing or stale the newest complete directory is found by scanning.
"""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import torch

from roomlight.errors import InputFileError
# Run folders are read by inference code too, so their layout lives in roomlight.prior.model.runs.
from roomlight.prior.model.runs import OPTIMIZER_NAME, STATE_NAME, latest_checkpoint, load_run_model, resolve_run_model

__all__ = ["atomic_write_text", "replace_dir", "optimizer_to_tensors", "optimizer_from_tensors",
           "save_training_state", "load_training_state", "latest_checkpoint", "checkpoint_name",
           "prune_checkpoints", "checkpoint_paths", "publish_checkpoint", "resolve_run_model", "load_run_model"]

def checkpoint_name(step: int) -> str:
    """Directory name of the checkpoint after ``step`` optimiser steps."""
    return f"step-{step:08d}"


def atomic_write_text(path: str | Path, text: str) -> None:
    """Write ``text`` to ``path`` via a temporary file, fsync and ``os.replace``."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.tmp-{os.getpid()}")
    with open(tmp, "w") as f:
        f.write(text)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)


def replace_dir(tmp: Path, target: Path) -> None:
    """Move the finished directory ``tmp`` to ``target``, replacing an existing one.

    A directory cannot be renamed over a non-empty one, so an existing ``target`` is first moved
    aside to ``target.old`` and removed afterwards; readers fall back to ``.old`` if they find no
    ``target`` (see :func:`resolve_run_model`).
    """
    old = target.with_name(target.name + ".old")
    if old.exists():
        shutil.rmtree(old)
    if target.exists():
        os.replace(target, old)
    os.replace(tmp, target)
    if old.exists():
        shutil.rmtree(old)


# ---------------------------------------------------------------------- optimiser <-> tensors
def optimizer_to_tensors(state_dict: dict) -> tuple[dict[str, torch.Tensor], str]:
    """Split ``optimizer.state_dict()`` into named tensors and a JSON string of the rest."""
    tensors, scalars = {}, {}
    for pid, st in state_dict["state"].items():
        for k, v in st.items():
            if isinstance(v, torch.Tensor):
                tensors[f"state.{pid}.{k}"] = v.detach().to("cpu").contiguous()
            else:
                scalars[f"{pid}.{k}"] = v
    meta = {"param_groups": state_dict["param_groups"], "scalars": scalars}
    return tensors, json.dumps(meta)


def optimizer_from_tensors(tensors: dict[str, torch.Tensor], meta_json: str) -> dict:
    """Inverse of :func:`optimizer_to_tensors`: a dict for ``optimizer.load_state_dict``."""
    meta = json.loads(meta_json)
    state: dict = {}
    for key, v in tensors.items():
        _, pid, name = key.split(".", 2)
        state.setdefault(int(pid), {})[name] = v
    for key, v in meta["scalars"].items():
        pid, name = key.split(".", 1)
        state.setdefault(int(pid), {})[name] = v
    groups = meta["param_groups"]
    for g in groups:
        if "betas" in g:
            g["betas"] = tuple(g["betas"])
    return {"state": state, "param_groups": groups}


# ---------------------------------------------------------------------- save / load
def save_training_state(directory: Path, *, model, optimizer, train_config: dict, trainer_state: dict,
                        rng: dict[str, torch.Tensor], rank: int = 0, write_shared: bool = True) -> None:
    """Write the parts of a checkpoint into ``directory`` (an existing temporary directory).

    Every DDP rank calls this with its own ``rng``; only the rank with ``write_shared`` writes the
    model, optimiser and ``trainer_state.json`` (the latter last, as the completeness marker).
    """
    from safetensors.torch import save_file

    save_file({k: v.detach().cpu().contiguous() for k, v in rng.items()},
              str(directory / f"rng-rank{rank}.safetensors"))
    if not write_shared:
        return
    model.save_pretrained(directory, training_config=train_config)
    tensors, meta = optimizer_to_tensors(optimizer.state_dict())
    save_file(tensors, str(directory / OPTIMIZER_NAME), metadata={"optimizer": meta})
    atomic_write_text(directory / STATE_NAME, json.dumps(trainer_state, indent=2) + "\n")


def load_training_state(directory: Path, rank: int = 0) -> dict:
    """Read a checkpoint directory: ``trainer_state`` (dict), ``optimizer`` (state_dict),
    ``rng`` (name -> uint8 tensor of this rank) and ``model_dir`` (for ``from_pretrained``)."""
    from safetensors import safe_open
    from safetensors.torch import load_file

    directory = Path(directory)
    try:
        trainer_state = json.loads((directory / STATE_NAME).read_text())
        with safe_open(str(directory / OPTIMIZER_NAME), framework="pt") as f:
            meta = f.metadata()["optimizer"]
            tensors = {k: f.get_tensor(k) for k in f.keys()}
        rng_path = directory / f"rng-rank{rank}.safetensors"
        rng = load_file(str(rng_path)) if rng_path.exists() else {}
    except (OSError, KeyError, json.JSONDecodeError) as e:
        raise InputFileError(directory, f"incomplete or corrupt checkpoint ({e})",
                             "delete this directory to resume from the previous checkpoint") from None
    return {"trainer_state": trainer_state, "optimizer": optimizer_from_tensors(tensors, meta), "rng": rng,
            "model_dir": directory}


def checkpoint_paths(run_dir: str | Path, step: int) -> tuple[Path, Path]:
    """(final, temporary) directories of the checkpoint after ``step`` steps in ``run_dir``."""
    ckdir = Path(run_dir) / "checkpoints"
    name = checkpoint_name(step)
    return ckdir / name, ckdir / f".tmp-{name}"


def publish_checkpoint(run_dir: str | Path, tmp: Path, final: Path, step: int, keep: int) -> None:
    """Move the finished ``tmp`` checkpoint to ``final``, point ``latest.json`` at it and keep the
    newest ``keep`` periodic checkpoints."""
    replace_dir(tmp, final)
    atomic_write_text(final.parent / "latest.json", json.dumps({"name": final.name, "step": step}) + "\n")
    prune_checkpoints(run_dir, keep)


def prune_checkpoints(run_dir: str | Path, keep: int) -> None:
    """Delete all but the ``keep`` newest periodic checkpoints (and stale temporary directories)."""
    ckdir = Path(run_dir) / "checkpoints"
    dirs = sorted(p for p in ckdir.glob("step-*") if p.is_dir())
    for d in dirs[:-keep] if keep > 0 else []:
        shutil.rmtree(d, ignore_errors=True)
    for tmp in ckdir.glob(".tmp-*"):
        shutil.rmtree(tmp, ignore_errors=True)
