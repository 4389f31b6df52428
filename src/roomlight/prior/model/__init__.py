"""The illumination prior: a panoramic VAE over HDR radiance + radial depth (paper §3.2-3.3).

- :class:`ModelConfig` / :func:`get_preset`  architecture (``default`` is the paper's network)
- :class:`PanoVAE`                         the network, encode/decode, checkpoints
- :class:`Normalization`                   log transforms + dataset statistics
- :class:`DiagonalGaussian`                the posterior q(z | x)
- :func:`load_run_model`                   ``--model PATH`` (a checkpoint, a training run, the authors' run)
- :func:`convert_authors_checkpoint`       the authors' ``config.yaml`` + ``.pth`` -> safetensors

See docs/model.md.
"""

from __future__ import annotations

from roomlight.prior.model.config import PRESETS, ModelConfig, get_preset
from roomlight.prior.model.convert import (
    AUTHORS_NORMALIZATION,
    ThirdPartyCheckpointWarning,
    from_authors_state_dict,
    to_authors_state_dict,
)
from roomlight.prior.model.distributions import DiagonalGaussian
from roomlight.prior.model.normalization import Normalization
from roomlight.prior.model.networks import Decoder, Encoder
from roomlight.prior.model.panovae import PanoVAE
from roomlight.prior.model.runs import convert_authors_checkpoint, load_run_model, resolve_run_model
from roomlight.prior.model.view_encoder import ViewEncoder

__all__ = [
    "ModelConfig", "PRESETS", "get_preset", "PanoVAE", "Encoder", "Decoder", "Normalization",
    "DiagonalGaussian", "AUTHORS_NORMALIZATION", "ThirdPartyCheckpointWarning",
    "convert_authors_checkpoint", "from_authors_state_dict", "to_authors_state_dict", "load_run_model",
    "resolve_run_model", "ViewEncoder",
]
