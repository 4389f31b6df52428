"""Saving and restoring a fit in progress, so an interrupted fit resumes where it stopped.

One ``safetensors`` file holds the trainable parameters of the light model (the frozen decoder
is not copied), the best iterate's values of the same parameters, Adam's moments and step
counts, and the pixel-subset generator's state; its metadata holds, as JSON, the iteration to
continue from, the best iterate's loss and iteration, the history so far, the counters of the
non-finite guard and the settings. It is written to a temporary name and renamed into place, so
a crash while saving leaves the previous state intact.

Resuming under other settings is refused: the iterations done so far would not be those of the
requested fit.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import torch

from roomlight.errors import RoomlightError

__all__ = ["save_fit_state", "load_fit_state"]

FORMAT = "roomlight.fit-state"
VERSION = 1


def _trainable(light) -> dict[str, torch.nn.Parameter]:
    return {name: p for name, p in light.named_parameters() if p.requires_grad}


def save_fit_state(path, fitter, next_iteration: int, best: tuple, history: list[dict], nonfinite: int,
                   in_a_row: int, tag: dict | None = None) -> None:
    """Write the state of ``fitter`` (a :class:`~roomlight.fitting.inverse.fitter.Fitter`) after
    ``next_iteration`` iterations; ``best`` is the run loop's (loss, iteration, state dict or None);
    ``tag`` describes what is being fitted (checked on loading)."""
    from safetensors.torch import save_file

    path = Path(path)
    tensors: dict[str, torch.Tensor] = {}
    params = _trainable(fitter.light)
    for name, p in params.items():
        tensors[f"param.{name}"] = p.detach().cpu().contiguous()
    if best[2] is not None:
        for name in params:
            tensors[f"best.{name}"] = best[2][name].detach().cpu().contiguous()
    opt = fitter.optimizer.state_dict()
    for idx, st in opt["state"].items():
        for key, value in st.items():
            if torch.is_tensor(value):
                tensors[f"opt.{idx}.{key}"] = value.detach().cpu().contiguous()
    tensors["rng"] = fitter.generator.get_state()
    meta = {"format": FORMAT, "version": VERSION, "next_iteration": int(next_iteration),
            "best_loss": best[0], "best_iteration": best[1], "history": history, "nonfinite": nonfinite,
            "in_a_row": in_a_row, "param_groups": opt["param_groups"], "parameters": list(params),
            "config": fitter.config.to_dict(), "tag": tag}
    tmp = path.with_name(f".{path.name}.tmp-{os.getpid()}")
    save_file(tensors, str(tmp), metadata={"state": json.dumps(meta)})
    os.replace(tmp, path)


def load_fit_state(path, fitter, tag: dict | None = None) -> dict:
    """Restore a state written by :func:`save_fit_state` into ``fitter`` (parameters, Adam, the
    generator) and return the run loop's bookkeeping: ``next_iteration``, ``best`` (loss,
    iteration, full state dict or None), ``history``, ``nonfinite``, ``in_a_row``."""
    from safetensors import safe_open

    path = Path(path)
    try:
        with safe_open(str(path), framework="pt") as f:
            meta = json.loads((f.metadata() or {}).get("state", "{}"))
            tensors = {k: f.get_tensor(k) for k in f.keys()}
    except Exception as exc:
        raise RoomlightError(f"{path}: cannot read the saved fit state ({str(exc).splitlines()[0]}); "
                             "delete it to start the fit over") from None
    if meta.get("format") != FORMAT:
        raise RoomlightError(f"{path}: not a roomlight fit state; delete it to start the fit over")
    if json.loads(json.dumps(tag)) != meta.get("tag"):
        raise RoomlightError(f"{path}: the saved fit is of another input or method; start over (delete the file, "
                             "or --restart) or write to another folder")
    if meta.get("config") != fitter.config.to_dict():
        changed = sorted(k for k in set(meta.get("config", {})) | set(fitter.config.to_dict())
                         if meta.get("config", {}).get(k) != fitter.config.to_dict().get(k))
        raise RoomlightError(f"{path}: the saved fit used other settings ({', '.join(changed)}); "
                             "start over (delete the file) or use the same settings")
    params = _trainable(fitter.light)
    if meta.get("parameters") != list(params):
        raise RoomlightError(f"{path}: the saved fit optimised other parameters; delete it to start the fit over")
    with torch.no_grad():
        for name, p in params.items():
            p.copy_(tensors[f"param.{name}"].to(p.device))
    best_state = None
    if any(k.startswith("best.") for k in tensors):
        import copy

        best_state = copy.deepcopy(fitter.light.state_dict())
        for name in params:
            best_state[name] = tensors[f"best.{name}"].to(best_state[name].device)
    state: dict = {}
    for key, value in tensors.items():
        if key.startswith("opt."):
            _, idx, name = key.split(".", 2)
            state.setdefault(int(idx), {})[name] = value
    fitter.optimizer.load_state_dict({"state": state, "param_groups": meta["param_groups"]})
    fitter.generator.set_state(tensors["rng"])
    return {"next_iteration": meta["next_iteration"], "best": (meta["best_loss"], meta["best_iteration"], best_state),
            "history": meta["history"], "nonfinite": meta["nonfinite"], "in_a_row": meta["in_a_row"]}
