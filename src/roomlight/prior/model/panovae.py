"""The panoramic convolutional VAE: the illumination prior (paper §3.2; conventions in docs/model.md).

A panorama of HDR radiance + radial depth is encoded into one global latent z (512-d by default)
and decoded back. Shapes for the default config (B = batch):

    encoder: x (B,4,128,256) ++ (cos θ, sin θ) -> stem 6->64 -> 4 x [stride-2 conv, ResBlock]
             -> GN -> SiLU -> conv to 32 ch at 8x16 -> flatten 4096 -> Linear -> (mean ‖ logvar)
    decoder: z (B,512) -> Linear -> 32x8x16 ++ (cos θ, sin θ) -> conv 34->256
             -> 4 x [nearest x2 + conv, AdaGN ResBlock] -> AdaGN -> SiLU -> conv to 4 ch

Checkpoints: :meth:`PanoVAE.save_pretrained` writes ``model.safetensors`` + ``config.json``;
:meth:`PanoVAE.from_pretrained` reads that or the authors' run folder (see
:mod:`roomlight.prior.model.convert`).
"""

from __future__ import annotations

from pathlib import Path

import torch
from torch import nn

from roomlight.errors import InputFileError, RoomlightError, ShapeError
from roomlight.prior.model.config import ModelConfig
from roomlight.prior.model.distributions import DiagonalGaussian
from roomlight.prior.model.networks import Decoder, Encoder
from roomlight.prior.model.normalization import Normalization
from roomlight.prior.model.saved import CONFIG_NAME, WEIGHTS_NAME, SavedPrior

__all__ = ["Encoder", "Decoder", "PanoVAE", "WEIGHTS_NAME", "CONFIG_NAME", "FORMAT_NAME"]

#: ``format`` field of our config.json, so that other JSON files are not mistaken for one.
FORMAT_NAME = "roomlight.panovae"
FORMAT_VERSION = 1


class PanoVAE(SavedPrior, nn.Module):
    """The prior. Holds its :class:`ModelConfig`, :class:`Normalization` and metadata.

    Args:
        config: architecture (default: the paper's network).
        normalization: input statistics; required by :meth:`encode` / :meth:`decode` (the
            ``*_normalized`` methods work without it).
        metadata: free-form JSON-able facts saved with the checkpoint. ``depth_units`` is
            ``"metres"`` for roomlight-trained models and ``"scale-free"`` for the authors'
            checkpoint (their depth has unit geometric-mean radius).
    """

    FORMAT, FORMAT_VERSION, CONFIG_CLASS = FORMAT_NAME, FORMAT_VERSION, ModelConfig

    def __init__(self, config: ModelConfig | None = None, normalization: Normalization | None = None,
                 metadata: dict | None = None):
        super().__init__()
        self.config = config or ModelConfig()
        self.normalization = normalization
        self.metadata = {"depth_units": "metres", **(metadata or {})}
        self.encoder = Encoder(self.config)
        self.decoder = Decoder(self.config)
        # Held in a tuple so that it is not a sub-module: the prior's state_dict, checksum and
        # device stay its own (the view encoder always runs on the CPU).
        self._view_encoder: tuple = ()
        self._depth_optional_view_encoder: tuple = ()
        self._weights_sha256: str | None = None

    @property
    def view_encoder(self):
        """The :class:`~roomlight.prior.model.view_encoder.ViewEncoder` trained for this prior, or None."""
        return self._view_encoder[0] if self._view_encoder else None

    def set_view_encoder(self, encoder) -> None:
        """Attach a view encoder (None detaches); it must share this prior's architecture."""
        self._view_encoder = self._held_encoder(encoder, "set_view_encoder")

    def _held_encoder(self, encoder, caller: str) -> tuple:
        """``encoder`` as held beside the prior: () for None, else (it on the CPU, in eval mode), refused
        when made for another prior architecture."""
        if encoder is None:
            return ()
        if encoder.config != self.config:
            raise RoomlightError(f"{caller}: the view encoder was made for another prior architecture")
        return (encoder.to("cpu").eval(),)

    @property
    def depth_optional_view_encoder(self):
        """The view encoder trained for this prior with depth withheld from half its views (it reads a
        photograph without a depth map; ``roomlight estimate`` uses it), or None."""
        return self._depth_optional_view_encoder[0] if self._depth_optional_view_encoder else None

    def set_depth_optional_view_encoder(self, encoder) -> None:
        """Attach a depth-optional view encoder (None detaches); same rules as :meth:`set_view_encoder`."""
        self._depth_optional_view_encoder = self._held_encoder(encoder, "set_depth_optional_view_encoder")

    # ------------------------------------------------------------------ normalised domain
    def _check_input(self, x: torch.Tensor, channels: int, what: str) -> None:
        h, w = self.config.resolution
        if x.dim() != 4 or x.shape[1] != channels or tuple(x.shape[-2:]) != (h, w):
            raise ShapeError(
                f"{what}: expected shape (B, {channels}, {h}, {w}), got {tuple(x.shape)} "
                f"(resample panoramas to {h}x{w} first; this model's resolution is fixed)"
            )

    def encode_normalized(self, x: torch.Tensor) -> DiagonalGaussian:
        """x (B, 4, H, W) z-scored -> posterior over z with (B, latent_dim) mean and logvar."""
        self._check_input(x, self.config.in_channels, "encode_normalized: x")
        mean, logvar = self._batched(self.encoder, x).chunk(2, dim=1)
        lo, hi = self.config.logvar_range
        return DiagonalGaussian(mean, logvar.clamp(lo, hi))

    def decode_normalized(self, z: torch.Tensor) -> torch.Tensor:
        """z (B, latent_dim) -> x_hat (B, 4, H, W) in the z-scored domain (no activation)."""
        if z.dim() != 2 or z.shape[1] != self.config.latent_dim:
            raise ShapeError(
                f"decode: expected z of shape (B, {self.config.latent_dim}), got {tuple(z.shape)}"
            )
        return self._batched(self.decoder, z)

    def _batched(self, net: nn.Module, x: torch.Tensor) -> torch.Tensor:
        """net(x) for a batch; on the CPU without autograd, one sample at a time.

        Why: a CPU decode of 32 panoramas at once costs ~1.9x more per panorama than 32 decodes
        of one (212 vs 109-117 ms, default model, 2 threads), because a batch's full-resolution
        feature maps (32 x 8 MiB per layer) fall out of cache. With autograd the whole graph is
        kept anyway, so training and fitting run the batch whole.
        """
        needs_graph = torch.is_grad_enabled() and (
            x.requires_grad or any(p.requires_grad for p in net.parameters()))
        if x.shape[0] <= 1 or x.device.type != "cpu" or needs_graph:
            return net(x)
        return torch.cat([net(x[i:i + 1]) for i in range(x.shape[0])])

    def forward_normalized(self, x: torch.Tensor, sample: bool | None = None,
                           generator: torch.Generator | None = None,
                           ) -> tuple[torch.Tensor, DiagonalGaussian]:
        """Reconstruct z-scored panoramas: x (B, 4, H, W) -> (x_hat (B, 4, H, W), posterior).

        ``sample`` selects a reparameterised sample (default while training) or the posterior
        mean (default in eval mode). The latitude channels are appended inside.
        """
        posterior = self.encode_normalized(x)
        return self.decode_normalized(self._posterior_latent(posterior, sample, generator)), posterior

    forward = forward_normalized

    # ------------------------------------------------------------------ physical domain
    def encode(self, radiance: torch.Tensor, depth: torch.Tensor) -> DiagonalGaussian:
        """Posterior for linear radiance (B, 3, H, W) and radial depth (B, 1, H, W).

        Depth must be in :attr:`metadata` ``["depth_units"]`` (metres, or scale-free for the
        authors' model: divide by the geometric mean first).
        """
        return self.encode_normalized(self._require_normalization().normalize(radiance, depth))

    def decode(self, z: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """z (B, latent_dim) -> (radiance (B, 3, H, W) linear in [0, 1e6], depth (B, 1, H, W) > 0)."""
        return self._require_normalization().denormalize(self.decode_normalized(z))

    # ------------------------------------------------------------------ checkpoints
    @classmethod
    def from_pretrained(cls, path: str | Path, device: str | torch.device = "cpu") -> "PanoVAE":
        """Load a model saved by :meth:`save_pretrained`, or the authors' run folder.

        ``path`` may be the checkpoint directory or a file inside it (``config.json``,
        ``model.safetensors``, ``config.yaml``, ``last_epoch.pth``). The authors' format is
        recognised by ``config.yaml`` + a ``.pth`` file; it is a third-party pickle and is loaded
        with ``weights_only=True`` (a warning says so). A ``view_encoder/`` folder beside the
        weights, trained for them, is loaded as :attr:`view_encoder`, and a ``view_encoder_depth_optional/``
        as :attr:`depth_optional_view_encoder`. Returns the model in eval mode.
        """
        path = Path(path)
        if not path.exists():
            raise InputFileError(path, "no such file or directory", "pass a checkpoint directory")
        directory = path if path.is_dir() else path.parent
        if (directory / CONFIG_NAME).exists() and (directory / WEIGHTS_NAME).exists():
            model = cls._load_saved(directory)
            from roomlight.prior.model.view_encoder import DEPTH_OPTIONAL_DIR, load_view_encoder_beside

            # the weights' checksum was verified while loading them: no second pass over the file
            model.set_view_encoder(load_view_encoder_beside(directory, model.config, model._weights_sha256))
            model.set_depth_optional_view_encoder(load_view_encoder_beside(
                directory, model.config, model._weights_sha256, name=DEPTH_OPTIONAL_DIR))
        elif (directory / "config.yaml").exists() or path.suffix == ".pth":
            from roomlight.prior.model.convert import load_authors_run

            model = load_authors_run(path, cls=cls)
        else:
            raise InputFileError(
                directory, f"not a checkpoint: expected {CONFIG_NAME} + {WEIGHTS_NAME} (roomlight) "
                "or config.yaml + last_epoch.pth (the authors' run folder)",
                "point at the folder written by save_pretrained or `roomlight convert`",
            )
        return model.to(device).eval()
