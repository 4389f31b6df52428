"""Architecture configuration of the panoramic VAE (paper §3.2, supp. "Training details").

One dataclass describes the network; it is saved in every checkpoint's ``config.json`` and is
the single source of truth for every shape in :mod:`roomlight.prior.model.panovae`.
"""

from __future__ import annotations

from dataclasses import dataclass

from roomlight.core.config import StrictConfig
from roomlight.errors import RoomlightError

__all__ = ["ModelConfig", "PRESETS", "get_preset"]


@dataclass(frozen=True)
class ModelConfig(StrictConfig):
    """Shapes and hyper-parameters of :class:`~roomlight.prior.model.panovae.PanoVAE`.

    The defaults are the paper's network (13,918,628 parameters).
    """

    #: (H, W) of the panoramas the network encodes and decodes; W = 2 H.
    resolution: tuple[int, int] = (128, 256)
    #: Dimension of the global latent code z.
    latent_dim: int = 512
    #: Base channel width (width of the encoder stem).
    ch: int = 64
    #: Per-stage channel multipliers; each stage halves the resolution.
    ch_mult: tuple[int, ...] = (1, 2, 4, 4)
    #: Residual blocks per encoder/decoder stage.
    num_res_blocks: int = 1
    #: Channels of the bottleneck feature map that is flattened into the linear head.
    z_channels: int = 32
    #: Number of GroupNorm / AdaGN groups; must divide every normalised channel count.
    norm_groups: int = 8
    #: Data channels (log1p R, G, B, log depth); the two latitude channels come on top.
    in_channels: int = 4
    #: Range the posterior log-variance is clamped to, for numerical safety.
    logvar_range: tuple[float, float] = (-30.0, 20.0)
    #: GroupNorm epsilon (the authors use 1e-6 everywhere).
    norm_eps: float = 1e-6
    #: Decoder norms are AdaGN conditioned on z (paper §3.2). False (an ablation): plain affine
    #: GroupNorms, so z reaches the decoder only through its first linear layer.
    adagn: bool = True
    #: Append (cos θ, sin θ) to the encoder's and the decoder's inputs (paper §3.2). False (an
    #: ablation): the convolutions see no latitude.
    latitude: bool = True

    def __post_init__(self) -> None:
        # Normalise sequences coming from JSON/YAML (lists) to tuples so configs compare equal.
        object.__setattr__(self, "resolution", tuple(int(v) for v in self.resolution))
        object.__setattr__(self, "ch_mult", tuple(int(v) for v in self.ch_mult))
        object.__setattr__(self, "logvar_range", tuple(float(v) for v in self.logvar_range))
        self.validate()

    # ------------------------------------------------------------------ derived shapes
    @property
    def num_stages(self) -> int:
        """Number of down-/up-sampling stages."""
        return len(self.ch_mult)

    @property
    def downsample_factor(self) -> int:
        """Total spatial reduction between the input and the bottleneck (16 by default)."""
        return 2 ** self.num_stages

    @property
    def bottleneck_resolution(self) -> tuple[int, int]:
        """(h, w) of the bottleneck feature map (8 x 16 by default)."""
        h, w = self.resolution
        return h // self.downsample_factor, w // self.downsample_factor

    @property
    def bottleneck_features(self) -> int:
        """Length of the flattened bottleneck, z_channels * h * w (4096 by default)."""
        h, w = self.bottleneck_resolution
        return self.z_channels * h * w

    @property
    def latitude_channels(self) -> int:
        """Channels appended to the encoder's and decoder's inputs: 2 with :attr:`latitude`, else 0."""
        return 2 if self.latitude else 0

    @property
    def encoder_channels(self) -> list[int]:
        """Channel width before each encoder stage followed by the width after the last one.

        For the default config: [64, 64, 128, 256, 256]; stage k maps entry k to entry k + 1.
        The decoder walks the same list backwards.
        """
        return [self.ch] + [self.ch * m for m in self.ch_mult]

    # ------------------------------------------------------------------ validation
    def validate(self) -> None:
        """Raise :class:`RoomlightError` if the configuration cannot build a network."""
        def bad(what: str, fix: str) -> RoomlightError:
            return RoomlightError(f"ModelConfig: {what} ({fix})")

        if len(self.resolution) != 2:
            raise bad(f"resolution must be (H, W), got {self.resolution}", "e.g. (128, 256)")
        h, w = self.resolution
        if h <= 0 or w != 2 * h:
            raise bad(f"resolution must satisfy W = 2 H, got {h}x{w}", f"use ({h}, {2 * h})")
        if not self.ch_mult or any(m <= 0 for m in self.ch_mult):
            raise bad(f"ch_mult must be non-empty and positive, got {self.ch_mult}", "e.g. (1, 2, 4, 4)")
        f = self.downsample_factor
        if h % f:
            raise bad(
                f"resolution {h}x{w} is not divisible by the downsampling factor {f} "
                f"(2 ** len(ch_mult))", f"use a height that is a multiple of {f}",
            )
        for name in ("latent_dim", "ch", "z_channels", "norm_groups", "in_channels"):
            if getattr(self, name) <= 0:
                raise bad(f"{name} must be positive, got {getattr(self, name)}", "use a positive integer")
        if self.num_res_blocks < 0:
            raise bad(f"num_res_blocks must be >= 0, got {self.num_res_blocks}", "use 0 or more")
        for c in sorted(set(self.encoder_channels)):
            if c % self.norm_groups:
                raise bad(
                    f"norm_groups={self.norm_groups} does not divide the channel width {c}",
                    "choose norm_groups dividing ch * every ch_mult entry",
                )
        lo, hi = self.logvar_range
        if not lo < hi:
            raise bad(f"logvar_range must be (low, high) with low < high, got {self.logvar_range}",
                      "e.g. (-30, 20)")

    # ------------------------------------------------------------------ (de)serialisation
    # to_dict / from_dict / override come from StrictConfig: unknown fields and wrong types are
    # refused with the field's path (``ModelConfig.ch: expected int, got str '32'``).

    @classmethod
    def preset(cls, name: str) -> "ModelConfig":
        """Named configuration; see :data:`PRESETS`."""
        return get_preset(name)


#: Named configurations. ``default`` is the paper's network; ``small`` is a cheaper network for
#: quick experiments at 64 x 128 (2.3 M params); ``compact`` is a 32 x 64 network that a
#: 2-core CPU trains for many epochs within an hour; ``lite`` is a 64 x 128 network whose
#: full-resolution stage is only 16 channels wide (the stages below cost what ``compact``
#: costs), made for CPU training at the emitter resolution; ``tiny`` is a toy network for tests
#: (16 x 32, 21,624 params).
PRESETS: dict[str, ModelConfig] = {
    "default": ModelConfig(),
    "small": ModelConfig(
        resolution=(64, 128), latent_dim=256, ch=32, ch_mult=(1, 2, 4, 4), z_channels=16,
        norm_groups=8,
    ),
    "compact": ModelConfig(
        resolution=(32, 64), latent_dim=128, ch=32, ch_mult=(1, 2, 4), z_channels=16, norm_groups=8,
    ),
    "lite": ModelConfig(
        resolution=(64, 128), latent_dim=128, ch=16, ch_mult=(1, 2, 4, 8), z_channels=16, norm_groups=8,
    ),
    "tiny": ModelConfig(
        resolution=(16, 32), latent_dim=16, ch=8, ch_mult=(1, 2), z_channels=4, norm_groups=4,
    ),
}


def get_preset(name: str) -> ModelConfig:
    """Return the preset called ``name`` (``default``, ``small``, ``compact`` or ``tiny``)."""
    try:
        return PRESETS[name]
    except KeyError:
        raise RoomlightError(
            f"unknown model preset {name!r}; choose one of {sorted(PRESETS)}"
        ) from None
