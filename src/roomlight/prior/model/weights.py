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


#: The top-level fields of a checkpoint's ``config.json`` (anything else is refused as a typo).
CONFIG_KEYS = ("format", "format_version", "roomlight_version", "model", "normalization", "metadata", "training",
               "weights_sha256")


def file_sha256(path) -> str:
    """Hex SHA-256 of a file, read in 1 MiB blocks."""
    import hashlib

    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def load_weights_file(path, sha256: str | None = None) -> dict:
    """The tensors of a ``.safetensors`` file; a corrupt, truncated or empty file, or one whose
    SHA-256 differs from ``sha256`` (when given), raises :class:`InputFileError` naming it."""
    from pathlib import Path

    from safetensors.torch import load_file

    path = Path(path)
    if sha256 is not None:
        actual = file_sha256(path)
        if actual != sha256:
            raise InputFileError(path, f"checksum mismatch: config.json records sha256 {sha256[:12]}..., the "
                                 f"file has {actual[:12]}... (truncated, corrupt or replaced)",
                                 "copy the checkpoint folder again, or retrain")
    if path.stat().st_size == 0:
        raise InputFileError(path, "empty weights file", "copy the checkpoint folder again, or retrain")
    try:
        return load_file(str(path))
    except Exception as exc:  # safetensors raises its own SafetensorError, or OSError/ValueError
        raise InputFileError(path, f"not a readable safetensors file ({str(exc).splitlines()[0][:120]})",
                             "copy the checkpoint folder again, or retrain") from None


def _config_field(directory, key: str):
    """Field ``key`` of a checkpoint folder's ``config.json`` (None when the file is absent,
    unreadable, not an object or has no such field)."""
    import json
    from pathlib import Path

    try:
        return json.loads((Path(directory) / "config.json").read_text(encoding="utf-8")).get(key)
    except (OSError, ValueError, AttributeError):
        return None


def checkpoint_format_version(directory) -> int | None:
    """The ``format_version`` of a checkpoint folder's ``config.json`` (None without an integer one)."""
    version = _config_field(directory, "format_version")
    return version if isinstance(version, int) else None


def checkpoint_format(directory) -> str | None:
    """The ``format`` field of a checkpoint folder's ``config.json``: which model family wrote it
    (None when the file is absent, unreadable or has none, as in the authors' run folders)."""
    return _config_field(directory, "format")


def read_config_json(path, format_name: str, format_version: int) -> dict:
    """The JSON object of a checkpoint's ``config.json`` whose ``format`` is ``format_name`` and whose
    ``format_version`` is at most ``format_version``; anything else raises :class:`InputFileError`
    naming the file."""
    import json
    from pathlib import Path

    path = Path(path)
    try:
        meta = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as e:
        raise InputFileError(path, f"cannot read JSON ({e})") from None
    if not isinstance(meta, dict) or meta.get("format") != format_name:
        found = meta.get("format") if isinstance(meta, dict) else type(meta).__name__
        raise InputFileError(path, f"format is {found!r}, expected {format_name!r}")
    version = meta.get("format_version", 0)
    if not isinstance(version, int) or version > format_version:
        raise InputFileError(path, f"format_version {version!r} is not one this roomlight understands "
                             f"({format_version})", "upgrade roomlight")
    return meta
