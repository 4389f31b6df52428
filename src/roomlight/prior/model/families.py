"""The prior's two model families behind one set of names: the paper's panoramic VAE
(:class:`~roomlight.prior.model.panovae.PanoVAE`) and VENI / VENI+D (:class:`~roomlight.prior.model.veni.VeniVAE`).

Presets are looked up by name in both families (``lite``, ``default``, ... and ``veni``, ``veni-d``,
...), models are built from their configuration's type, and a checkpoint folder is loaded by the
``format`` its ``config.json`` declares, so that every ``--model PATH`` accepts either family.
"""

from __future__ import annotations

from pathlib import Path

from roomlight.errors import RoomlightError
from roomlight.prior.model.config import PRESETS, ModelConfig
from roomlight.prior.model.veni import VENI_FORMAT, VENI_PRESETS, VeniConfig, VeniVAE
from roomlight.prior.model.weights import checkpoint_format

__all__ = ["model_preset", "build_model", "load_model", "is_veni", "ALL_PRESETS"]

#: Every architecture preset by name.
ALL_PRESETS: dict[str, ModelConfig | VeniConfig] = {**PRESETS, **VENI_PRESETS}


def model_preset(name: str) -> ModelConfig | VeniConfig:
    """The architecture called ``name`` in either family."""
    try:
        return ALL_PRESETS[name]
    except KeyError:
        raise RoomlightError(f"unknown model preset {name!r}; choose one of {sorted(ALL_PRESETS)}") from None


def build_model(config: ModelConfig | VeniConfig, normalization=None, metadata: dict | None = None):
    """A freshly initialised model of the family ``config`` belongs to."""
    if isinstance(config, VeniConfig):
        return VeniVAE(config, normalization, metadata)
    from roomlight.prior.model.panovae import PanoVAE

    return PanoVAE(config, normalization, metadata)


def load_model(path: str | Path, device="cpu"):
    """Load a checkpoint folder (or a file in it) of either family, by its config.json's ``format``."""
    path = Path(path)
    directory = path if path.is_dir() else path.parent
    if checkpoint_format(directory) == VENI_FORMAT:
        return VeniVAE.from_pretrained(directory, device=device)
    from roomlight.prior.model.panovae import PanoVAE

    return PanoVAE.from_pretrained(path, device=device)


def is_veni(model) -> bool:
    """True for VENI and VENI+D models."""
    return isinstance(model, VeniVAE)
