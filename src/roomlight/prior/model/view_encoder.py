"""The view encoder: what a photograph shows -> the prior's latent z and a log exposure.

The input is a :class:`~roomlight.core.geometry.lift.PartialPanorama` made into five channels at the
prior's resolution (:func:`view_input`):

    (log1p R, log1p G, log1p B, log D) z-scored with the prior's statistics, 0 where unseen,
    and the seen mask (1 / 0).

Without a depth map (``view_input(..., depth=False)``) the log D channel is 0 everywhere, which a
z-scored map never is over a whole view; an encoder trained with depth withheld from part of its views
(``ViewTrainConfig.depth_dropout`` > 0; :attr:`ViewEncoder.reads_without_depth`) reads such an input as
"depth unknown" and predicts the room's size from what it sees. Encoders trained without that were never
shown it.

Radiance is first divided by the view's own log-average luminance ``k`` (over seen cells that
are not saturated), because a photograph's units are arbitrary. The network predicts z and
``s``: the light in the units of the photograph is ``k · e^s · decode(z).radiance``; depth is in
the photograph's metres.

The backbone is the prior's encoder (:class:`~roomlight.prior.model.networks.Encoder`) with one more
input channel; its weights start from the prior's encoder (the mask channel's weights at 0), so
an untrained view encoder already reads a seen part of a room as the prior would.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import torch
from torch import nn

from roomlight.core.color import LOG_EPS, luminance_torch
from roomlight.errors import InputFileError
from roomlight.core.geometry.lift import PartialPanorama
from roomlight.prior.model.config import ModelConfig
from roomlight.prior.model.networks import Encoder
from roomlight.prior.model.normalization import Normalization
from roomlight.prior.model.weights import file_sha256, load_state_dict_checked, load_weights_file, read_config_json

__all__ = ["ViewEncoder", "view_input", "view_exposure", "load_view_encoder_beside", "VIEW_ENCODER_DIR",
           "DEPTH_OPTIONAL_DIR", "DEPTH_CHANNEL", "SEEN_CHANNEL", "withhold_depth", "FORMAT_NAME", "SATURATION"]

#: Where a prior's view encoder lives, inside the prior's model folder.
VIEW_ENCODER_DIR = "view_encoder"
#: Where a prior's depth-optional view encoder lives (trained with depth withheld from half its views):
#: what ``roomlight estimate`` reads a photograph without a depth map with.
DEPTH_OPTIONAL_DIR = "view_encoder_depth_optional"
#: Index of the log-depth channel in the network's input.
DEPTH_CHANNEL = 3
#: Index of the channel that marks the cells a view shows (1) in the network's input.
SEEN_CHANNEL = 4
FORMAT_NAME = "roomlight.view-encoder"
FORMAT_VERSION = 1
WEIGHTS_NAME = "model.safetensors"
CONFIG_NAME = "config.json"
#: A cell whose mean radiance reaches this in any channel counts as saturated (photos clip at 1).
SATURATION = 0.99


def view_exposure(partial: PartialPanorama, saturation: float = SATURATION) -> float:
    """``k``: the log-average luminance of the seen, unsaturated cells (1 when there are none)."""
    rad = partial.radiance.permute(1, 2, 0)
    keep = partial.seen & (rad.amax(-1) < saturation)
    if not bool(keep.any()):
        keep = partial.seen
    if not bool(keep.any()):
        return 1.0
    y = luminance_torch(rad[keep].double().T[:, :, None])[:, 0]
    return float(torch.exp(torch.log(y + LOG_EPS).mean()))


def view_input(partial: PartialPanorama, normalization: Normalization, exposure: float | None = None,
               depth: bool = True) -> tuple[torch.Tensor, float]:
    """The network's input (5, H, W) for a partial panorama, and the ``k`` it was divided by.

    ``depth=False``: the partial panorama's depth is not known (a photograph without a depth map, lifted
    at any distance: the directions do not depend on it); the log-depth channel is 0 everywhere."""
    k = view_exposure(partial) if exposure is None else float(exposure)
    seen = partial.seen
    depth_m = torch.where(seen[None], partial.log_depth.exp(), torch.ones_like(partial.log_depth))
    x = normalization.normalize((partial.radiance / k)[None], depth_m[None])[0]
    x = x * seen[None].to(x.dtype)
    if not depth:
        x = withhold_depth(x)
    return torch.cat([x, seen[None].to(x.dtype)], dim=0), k


def withhold_depth(x: torch.Tensor) -> torch.Tensor:
    """A copy of network inputs (..., C, H, W) with the log-depth channel set to 0 (depth unknown)."""
    x = x.clone()
    x[..., DEPTH_CHANNEL, :, :] = 0.0
    return x


class ViewEncoder(nn.Module):
    """x (B, 5, H, W) -> (z (B, latent_dim), s (B,)) for the prior whose ``config`` it shares.

    Args:
        config: the prior's :class:`ModelConfig` (resolution, widths, latent size).
    """

    def __init__(self, config: ModelConfig):
        super().__init__()
        self.config = config
        self.backbone = Encoder(dataclasses.replace(config, in_channels=config.in_channels + 1))
        # The backbone's own head (to_moments) is replaced by these two.
        del self.backbone.to_moments
        self.to_latent = nn.Linear(config.bottleneck_features, config.latent_dim)
        self.to_exposure = nn.Linear(config.bottleneck_features, 1)
        nn.init.zeros_(self.to_exposure.weight)
        nn.init.zeros_(self.to_exposure.bias)

    def forward(self, x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        h = self.backbone.feature_maps(x)[-1].flatten(1)
        return self.to_latent(h), self.to_exposure(h)[:, 0]

    @property
    def reads_without_depth(self) -> bool:
        """Whether it was trained with depth withheld from some of its views (module docstring)."""
        training = (getattr(self, "metadata", None) or {}).get("training") or {}
        return float(training.get("depth_dropout", 0.0)) > 0.0

    @classmethod
    def from_prior(cls, prior) -> "ViewEncoder":
        """A view encoder whose weights start from the prior's encoder (module docstring)."""
        net = cls(prior.config)
        src = prior.encoder.state_dict()
        own = net.backbone.state_dict()
        c = prior.config.in_channels
        for name, value in own.items():
            if name == "stem.conv.weight":  # input channels: c data, 1 mask, then latitude
                w = torch.zeros_like(value)
                w[:, :c] = src[name][:, :c]
                w[:, c + 1:] = src[name][:, c:]
                own[name] = w
            else:
                own[name] = src[name].clone()
        net.backbone.load_state_dict(own)
        d = prior.config.latent_dim
        with torch.no_grad():
            net.to_latent.weight.copy_(prior.encoder.to_moments.weight[:d])
            net.to_latent.bias.copy_(prior.encoder.to_moments.bias[:d])
        return net

    # ------------------------------------------------------------------ files
    #: SHA-256 of the prior's weights file this encoder was trained for (saved with it).
    prior_sha256: str | None = None

    def trained_for(self, prior_sha256: str | None) -> bool:
        """Whether this encoder may read for the prior whose weights have checksum ``prior_sha256``:
        false only when both checksums are known and differ (its latents would mean nothing there)."""
        return self.prior_sha256 is None or prior_sha256 is None or self.prior_sha256 == prior_sha256

    def save_pretrained(self, directory, training_config: dict | None = None) -> Path:
        """``model.safetensors`` + ``config.json`` in ``directory``; :attr:`prior_sha256` ties the
        encoder to the weights of the decoder it was trained for."""
        from safetensors.torch import save_file

        from roomlight import __version__

        directory = Path(directory)
        directory.mkdir(parents=True, exist_ok=True)
        tensors = {k: v.detach().cpu().contiguous() for k, v in self.state_dict().items()}
        save_file(tensors, str(directory / WEIGHTS_NAME), metadata={"format": FORMAT_NAME})
        meta = {"format": FORMAT_NAME, "format_version": FORMAT_VERSION, "roomlight_version": __version__,
                "model": self.config.to_dict(), "prior_weights_sha256": self.prior_sha256, "training": training_config,
                "weights_sha256": file_sha256(directory / WEIGHTS_NAME)}
        (directory / CONFIG_NAME).write_text(json.dumps(meta, indent=2, default=str) + "\n")
        return directory

    @classmethod
    def from_pretrained(cls, directory, prior_config: ModelConfig | None = None) -> "ViewEncoder":
        """Load a saved view encoder; with ``prior_config``, refuse one made for another architecture."""
        directory = Path(directory)
        cfg_path = directory / CONFIG_NAME
        meta = read_config_json(cfg_path, FORMAT_NAME, FORMAT_VERSION)
        config = ModelConfig.from_dict(meta.get("model"), where="view_encoder.model")
        if prior_config is not None and config != prior_config:
            raise InputFileError(cfg_path, "the view encoder was trained for another prior architecture",
                                 "retrain it with `roomlight train-view-encoder` for this prior")
        net = cls(config)
        state = load_weights_file(directory / WEIGHTS_NAME, sha256=meta.get("weights_sha256"))
        load_state_dict_checked(net, state, str(directory / WEIGHTS_NAME))
        net.prior_sha256 = meta.get("prior_weights_sha256")
        net.metadata = {k: meta.get(k) for k in ("training", "roomlight_version")}
        return net.eval()


def load_view_encoder_beside(prior_dir, prior_config: ModelConfig, prior_sha256: str | None = None,
                             name: str = VIEW_ENCODER_DIR) -> "ViewEncoder | None":
    """The view encoder in ``prior_dir/<name>/`` (``view_encoder/``, or :data:`DEPTH_OPTIONAL_DIR`), or
    None when there is none or it was trained for other prior weights (a warning says so: its latents
    would mean nothing to this decoder).

    ``prior_sha256``: the prior's weights checksum when the caller already verified it (the weights
    file is hashed otherwise)."""
    import warnings

    folder = Path(prior_dir) / name
    if not (folder / CONFIG_NAME).exists():
        return None
    encoder = ViewEncoder.from_pretrained(folder, prior_config)
    weights = Path(prior_dir) / WEIGHTS_NAME
    if encoder.prior_sha256 is not None and weights.exists() and \
            not encoder.trained_for(prior_sha256 or file_sha256(weights)):
        warnings.warn(f"{folder}: trained for other prior weights than {weights}; not used "
                      "(retrain it with `roomlight train-view-encoder`)", stacklevel=2)
        return None
    return encoder
