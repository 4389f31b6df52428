"""The paper authors' checkpoint format: key mapping, loader and converter.

Their run folder holds ``config.yaml`` (a ``model:`` section with our :class:`ModelConfig`
field names, plus ``train:`` and paths) and ``last_epoch.pth``, a ``torch.save`` pickle of
``{"epoch", "step", "state_dict"}`` (or a bare state_dict). Their network is ours with other
names: an ``nn.Sequential`` per half (``encoder.model.<i>`` / ``decoder.model.<i>``) plus the
top-level linears ``quant`` and ``post_quant``. Inside each block the names coincide with ours.

Their input normalisation is hard-coded in their code, so it is hard-coded here (and only here),
and their depth maps have unit geometric-mean radius: a loaded model records
``metadata["depth_units"] = "scale-free"``.

The index layout of the Sequentials is known exactly for the published config (one ResBlock per
stage, four stages): E.1 stem, E.2/4/6/8 stride-2 convs, E.3/5/7/9 ResBlocks, E.10 GroupNorm,
(E.11 SiLU), E.12 conv; D.1 conv, D.2/4/6/8 upsamples, D.3/5/7/9 AdaGN ResBlocks, D.10 AdaGN,
(D.11 SiLU), D.12 conv. For other configs we extrapolate the same pattern (1 + num_res_blocks
entries per stage).
"""

from __future__ import annotations

import warnings
from pathlib import Path

import torch

from roomlight.errors import InputFileError, RoomlightError
from roomlight.prior.model.config import ModelConfig
from roomlight.prior.model.normalization import Normalization
from roomlight.prior.model.weights import load_state_dict_checked

__all__ = [
    "AUTHORS_NORMALIZATION",
    "ThirdPartyCheckpointWarning",
    "authors_prefix_map",
    "to_authors_state_dict",
    "from_authors_state_dict",
    "read_authors_config",
    "load_authors_run",
]

#: The authors' hard-coded statistics of (log1p R, log1p G, log1p B, log depth).
AUTHORS_NORMALIZATION = Normalization(
    mean=(0.9586, 0.7788, 0.4920, 0.0020),
    std=(0.6250, 0.5933, 0.5579, 0.4601),
)

_E, _D = "encoder.model.", "decoder.model."
_CONFIG_FIELDS = ("resolution", "latent_dim", "ch", "ch_mult", "num_res_blocks", "z_channels",
                  "norm_groups")


class ThirdPartyCheckpointWarning(UserWarning):
    """Loading a pickle written by someone else (even with ``weights_only=True``)."""


def authors_prefix_map(cfg: ModelConfig) -> dict[str, str]:
    """Module prefixes: ours -> the authors' (each ends with '.'; block internals are shared)."""
    n = cfg.num_res_blocks
    m = {"encoder.stem.": f"{_E}1.", "decoder.stem.": f"{_D}1."}
    for k in range(cfg.num_stages):
        base = 2 + k * (1 + n)
        m[f"encoder.stages.{k}.down."] = f"{_E}{base}."
        m[f"decoder.stages.{k}.up."] = f"{_D}{base}."
        for r in range(n):
            m[f"encoder.stages.{k}.blocks.{r}."] = f"{_E}{base + 1 + r}."
            m[f"decoder.stages.{k}.blocks.{r}."] = f"{_D}{base + 1 + r}."
    head = 2 + cfg.num_stages * (1 + n)  # index of the final norm; +1 is SiLU, +2 the conv
    m["encoder.out_norm."] = f"{_E}{head}."
    m["encoder.out_conv."] = f"{_E}{head + 2}."
    m["decoder.out_norm."] = f"{_D}{head}."
    m["decoder.out_conv."] = f"{_D}{head + 2}."
    m["encoder.to_moments."] = "quant."
    m["decoder.from_latent."] = "post_quant."
    return m


def _rename(state: dict, prefixes: dict[str, str], source: str) -> dict:
    out, unknown = {}, []
    for key, value in state.items():
        for old, new in prefixes.items():
            if key.startswith(old):
                out[new + key[len(old):]] = value
                break
        else:
            unknown.append(key)
    if unknown:
        raise InputFileError(
            source, f"{len(unknown)} unrecognised weight name(s), e.g. {unknown[:3]}",
            "is this a checkpoint of the same architecture?",
        )
    return out


def _authors_sort_key(key: str) -> tuple:
    """Order of the authors' state_dict: E.<i>, D.<i>, quant, post_quant."""
    for rank, prefix in enumerate((_E, _D)):
        if key.startswith(prefix):
            return (rank, int(key[len(prefix):].split(".", 1)[0]))
    return (2 if key.startswith("quant.") else 3, 0)


def to_authors_state_dict(state: dict, cfg: ModelConfig) -> dict:
    """Rename our state_dict to the authors' keys (same tensors, their order)."""
    out = _rename(state, authors_prefix_map(cfg), "state_dict")
    # Stable sort keeps each block's internal order (norm1, norm2, conv1, conv2).
    return dict(sorted(out.items(), key=lambda kv: _authors_sort_key(kv[0])))


def from_authors_state_dict(state: dict, cfg: ModelConfig, source: str = "state_dict") -> dict:
    """Rename the authors' state_dict to our keys.

    DDP's ``module.`` and torch.compile's ``_orig_mod.`` prefixes are stripped first.
    """
    cleaned = {}
    for key, value in state.items():
        for junk in ("module.", "_orig_mod."):
            if key.startswith(junk):
                key = key[len(junk):]
        cleaned[key] = value
    inverse = {new: old for old, new in authors_prefix_map(cfg).items()}
    return _rename(cleaned, inverse, source)


def _yaml_loader():
    import yaml

    class Loader(yaml.SafeLoader):
        """SafeLoader that also reads ``!!python/tuple`` (yaml.dump of a tuple) as a list."""

    Loader.add_constructor(
        "tag:yaml.org,2002:python/tuple", lambda loader, node: loader.construct_sequence(node)
    )
    return Loader


def read_authors_config(path: str | Path) -> tuple[ModelConfig, dict]:
    """Parse the authors' ``config.yaml`` -> (ModelConfig, whole YAML as a dict).

    Block-style lists (one ``- item`` per line) and flow lists are both plain YAML. Missing
    model fields fall back to the paper's values; unknown ones are reported and ignored.
    """
    import yaml

    path = Path(path)
    try:
        doc = yaml.load(path.read_text(), Loader=_yaml_loader()) or {}
    except (OSError, yaml.YAMLError) as e:
        raise InputFileError(path, f"cannot parse YAML ({e})") from None
    if not isinstance(doc, dict) or not isinstance(doc.get("model", {}), dict):
        raise InputFileError(path, "expected a mapping with a 'model:' section")
    model = doc.get("model") or {}
    extra = sorted(set(model) - set(_CONFIG_FIELDS))
    if extra:
        warnings.warn(f"{path}: ignoring unknown model field(s) {extra}", stacklevel=2)
    try:
        cfg = ModelConfig(**{k: model[k] for k in _CONFIG_FIELDS if k in model})
    except (RoomlightError, TypeError, ValueError) as e:
        raise InputFileError(path, f"invalid model section: {e}") from None
    return cfg, doc


def _find_weights(directory: Path) -> Path:
    preferred = directory / "last_epoch.pth"
    if preferred.exists():
        return preferred
    candidates = sorted(directory.glob("*.pth")) + sorted(directory.glob("*.pt"))
    if len(candidates) == 1:
        return candidates[0]
    raise InputFileError(
        directory, "no last_epoch.pth" + (f" and several candidates {[c.name for c in candidates]}"
                                          if candidates else " (nor any .pth file)"),
        "pass the .pth file you want explicitly",
    )


def load_authors_run(path: str | Path, cls):
    """Load the authors' run folder (or its ``.pth`` file) into a model of class ``cls``.

    ``cls`` is :class:`roomlight.prior.model.PanoVAE` (or a subclass): it is passed in, rather than
    imported here, because ``PanoVAE.from_pretrained`` calls this function.

    ``config.yaml`` must sit next to the weights. The pickle is loaded on the CPU with
    ``weights_only=True``, which refuses arbitrary objects; a :class:`ThirdPartyCheckpointWarning`
    reminds the caller that it is a third-party pickle nonetheless (convert it once with
    :func:`roomlight.prior.model.runs.convert_authors_checkpoint` and share the safetensors instead).
    """
    path = Path(path)
    directory = path if path.is_dir() else path.parent
    weights = path if path.is_file() and path.suffix in (".pth", ".pt") else _find_weights(directory)
    cfg_path = directory / "config.yaml"
    if not cfg_path.exists():
        raise InputFileError(cfg_path, "missing", "the authors' config.yaml must sit next to the .pth")
    cfg, doc = read_authors_config(cfg_path)

    warnings.warn(
        f"{weights} is a pickle written by a third party; loading it with weights_only=True "
        "(no code is executed), but only use files from a source you trust. Convert it once with "
        "`roomlight convert` to get a pickle-free safetensors checkpoint.",
        ThirdPartyCheckpointWarning, stacklevel=2,
    )
    try:
        ckpt = torch.load(str(weights), map_location="cpu", weights_only=True)
    except Exception as e:  # torch raises several types (UnpicklingError, RuntimeError, ...)
        raise InputFileError(weights, f"cannot load the checkpoint ({type(e).__name__}: {e})") from None

    meta: dict = {"source": "authors", "depth_units": "scale-free", "source_path": str(weights)}
    if isinstance(ckpt, dict) and "state_dict" in ckpt:
        state = ckpt["state_dict"]
        for k in ("epoch", "step"):
            if k in ckpt and isinstance(ckpt[k], (int, float)):
                meta[k] = int(ckpt[k])
    else:
        state = ckpt
    if not isinstance(state, dict) or not all(isinstance(v, torch.Tensor) for v in state.values()):
        raise InputFileError(weights, "expected a state_dict (a dict of tensors) or a dict with "
                             "a 'state_dict' entry")
    if isinstance(doc.get("train"), dict):
        meta["training"] = doc["train"]

    model = cls(cfg, AUTHORS_NORMALIZATION, meta)
    state = from_authors_state_dict(state, cfg, str(weights))
    load_state_dict_checked(model, {k: v.float() for k, v in state.items()}, str(weights))
    return model
