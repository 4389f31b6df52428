"""Loading a state_dict into a model with an error that names what does not fit."""

from __future__ import annotations

from torch import nn

from roomlight.errors import InputFileError

__all__ = ["load_state_dict_checked"]


def load_state_dict_checked(model: nn.Module, state: dict, source: str) -> None:
    """``load_state_dict(strict=True)`` with an error that lists the first mismatches."""
    own = model.state_dict()
    missing = [k for k in own if k not in state]
    unexpected = [k for k in state if k not in own]
    wrong = [f"{k}: expected {tuple(own[k].shape)}, got {tuple(state[k].shape)}"
             for k in own if k in state and own[k].shape != state[k].shape]
    if missing or unexpected or wrong:
        parts = []
        if missing:
            parts.append(f"{len(missing)} missing (e.g. {missing[:3]})")
        if unexpected:
            parts.append(f"{len(unexpected)} unexpected (e.g. {unexpected[:3]})")
        if wrong:
            parts.append(f"{len(wrong)} with wrong shape (e.g. {wrong[:3]})")
        raise InputFileError(
            source, "weights do not match the model config: " + "; ".join(parts),
            "check that the config file belongs to these weights",
        )
    model.load_state_dict(state, strict=True)
