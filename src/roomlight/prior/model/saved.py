"""The checkpoint folder both prior families write and read: ``model.safetensors`` + ``config.json``.

``config.json`` holds the ``format`` (which family), its version, the architecture, the normalisation
statistics, free-form metadata, the training configuration and the weights' SHA-256, which loading
verifies. :class:`SavedPrior` gives a model class :meth:`~SavedPrior.save_pretrained` and the loading
of such a folder; the class says its format and configuration type.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

from roomlight.errors import InputFileError, RoomlightError
from roomlight.prior.model.normalization import Normalization
from roomlight.prior.model.weights import (CONFIG_KEYS, file_sha256, load_state_dict_checked, load_weights_file,
                                    read_config_json)

__all__ = ["SavedPrior", "WEIGHTS_NAME", "CONFIG_NAME"]

WEIGHTS_NAME = "model.safetensors"
CONFIG_NAME = "config.json"


class SavedPrior:
    """Mixin of a prior model with ``config``, ``normalization`` and ``metadata`` attributes.

    A subclass sets ``FORMAT`` (the ``format`` field), ``FORMAT_VERSION`` and ``CONFIG_CLASS`` (its
    architecture dataclass, with ``to_dict`` / ``from_dict``), and is built as
    ``cls(config, normalization, metadata)``.
    """

    FORMAT: str
    FORMAT_VERSION: int
    CONFIG_CLASS: type

    def _require_normalization(self) -> Normalization:
        """The input statistics :meth:`encode` / :meth:`decode` need; a clear error when unset."""
        if self.normalization is None:
            raise RoomlightError(
                f"{type(self).__name__} has no normalisation statistics; compute them with "
                "Normalization.from_data(...) and set model.normalization, or load a checkpoint")
        return self.normalization

    def _posterior_latent(self, posterior, sample: bool | None, generator=None):
        """The latent a reconstruction decodes: a reparameterised sample of ``posterior`` when
        ``sample`` (default: while training), else its mean."""
        if sample is None:
            sample = self.training
        return posterior.sample(generator) if sample else posterior.mode()

    def save_pretrained(self, directory: str | Path, training_config=None) -> Path:
        """Write ``model.safetensors`` + ``config.json`` into ``directory`` (created if needed).

        ``training_config`` (a dataclass or dict) is stored verbatim for provenance. Returns the
        directory. No pickle is involved, so the result is safe to share.
        """
        from safetensors.torch import save_file

        from roomlight import __version__

        directory = Path(directory)
        directory.mkdir(parents=True, exist_ok=True)
        if dataclasses.is_dataclass(training_config) and not isinstance(training_config, type):
            training_config = dataclasses.asdict(training_config)
        tensors = {k: v.detach().to("cpu").contiguous() for k, v in self.state_dict().items()}
        save_file(tensors, str(directory / WEIGHTS_NAME), metadata={"format": self.FORMAT})
        meta = {
            "format": self.FORMAT,
            "format_version": self.FORMAT_VERSION,
            "roomlight_version": __version__,
            "model": self.config.to_dict(),
            "normalization": None if self.normalization is None else self.normalization.to_dict(),
            "metadata": self.metadata,
            "training": training_config,
            "weights_sha256": file_sha256(directory / WEIGHTS_NAME),  # verified on load
        }
        (directory / CONFIG_NAME).write_text(json.dumps(meta, indent=2, default=str) + "\n")
        return directory

    @classmethod
    def _load_saved(cls, directory: Path):
        """The model saved in ``directory`` by :meth:`save_pretrained` (weights checksum verified)."""
        from roomlight.core.config import check_keys

        cfg_path = directory / CONFIG_NAME
        meta = read_config_json(cfg_path, cls.FORMAT, cls.FORMAT_VERSION)
        try:
            check_keys(meta, CONFIG_KEYS, "config")
            config = cls.CONFIG_CLASS.from_dict(meta.get("model"), where="config.model")
            norm = meta.get("normalization")
            norm = None if norm is None else Normalization.from_dict(norm)
        except RoomlightError as e:
            raise InputFileError(cfg_path, str(e)) from None
        except (TypeError, ValueError, KeyError, AttributeError) as e:
            raise InputFileError(cfg_path, f"config.normalization: not valid ({e})") from None
        sha = meta.get("weights_sha256")
        if sha is not None and not isinstance(sha, str):
            raise InputFileError(cfg_path, f"config.weights_sha256: expected str, got {sha!r}")
        metadata = dict(meta.get("metadata") or {})
        if meta.get("training") is not None:
            metadata.setdefault("training", meta["training"])
        metadata.setdefault("saved_with_roomlight", meta.get("roomlight_version"))
        model = cls(config, norm, metadata)
        # Checkpoints written before the checksum was recorded have none: they load unverified.
        state = load_weights_file(directory / WEIGHTS_NAME, sha256=sha)
        model._weights_sha256 = sha  # verified above (None for checkpoints saved before checksums)
        load_state_dict_checked(model, state, str(directory / WEIGHTS_NAME))
        return model
