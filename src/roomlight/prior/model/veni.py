"""VENI and VENI+D: a rotation-equivariant variational prior over panoramas (docs/model.md, "VENI").

Built from the published description of VENI (Walker et al., "VENI: Variational Encoder for Natural
Illumination", CVPR 2026): a Vector-Neuron vision transformer encoder whose projections are
SO(2)-equivariant (:mod:`roomlight.prior.model.equivariant`), and a conditional neural field decoder in the
manner of RENI++ whose output is the same under a joint rotation of the latent and the direction.
VENI decodes radiance only (an environment map); VENI+D also decodes radial depth, so that its
latent becomes a 2.5D area light through the same emitter and fitting code as our prior.

Shapes (B batch, H x W the panorama, N latent vectors, latent_dim = 3 N):

    encoder: x (B, C, H, W) z-scored (C = 3, or 4 with depth)
             -> W tokens, one per column; token j's channels are its H pixels, each the vector
                (ω_x, ω_z | ω_y, x_1..x_C): planar direction, then invariants
             -> SO2Linear (H -> channels) -> [CLS] + tokens -> blocks x VNBlock
             -> CLS -> SO2Linear heads: mean (B, N, 3), log-variance (B, N) (one per vector: isotropic)
    decoder: z (B, 3N) as Z (B, N, 3) = (x, y, z) per vector, directions ω (P, 3)
             -> per pixel   [<Z_i⊥, ω⊥>, Z_i⊥ × ω⊥ (i = 1..N), ω_y, |ω⊥|]   (invariant)
             -> per image   [Z_iy]                                        (added into every layer)
             -> linear -> sine -> residual MLP -> (B, C, H, W) z-scored

Rolling a panorama by k columns rotates its latent by δ = 2πk/W about the vertical axis
(:func:`rotate_latent`), and decoding a latent rotated by δ gives the decoded panorama rolled by k
columns: both exactly, up to float rounding (tests/test_veni.py).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import torch
from torch import nn

from roomlight.core.config import StrictConfig
from roomlight.errors import InputFileError, RoomlightError, ShapeError
from roomlight.core.geometry.equirect import pixel_directions
from roomlight.prior.model.distributions import DiagonalGaussian
from roomlight.prior.model.equivariant import SO2Linear, VNBlock
from roomlight.prior.model.normalization import Normalization
from roomlight.prior.model.saved import CONFIG_NAME, WEIGHTS_NAME, SavedPrior
from roomlight.prior.model.weights import checkpoint_format_version

__all__ = ["VeniConfig", "VENI_PRESETS", "VeniEncoder", "VeniField", "VeniVAE", "rotate_latent",
           "VENI_FORMAT"]

#: ``format`` of a VENI checkpoint's config.json (a PanoVAE's is ``roomlight.panovae``).
VENI_FORMAT = "roomlight.veni"
#: 2: the field's per-image inputs are Z_iy alone (version 1 also took |Z_i⊥|, which a posterior mean
#: puts outside what training showed the field; docs/model.md). Version 1 checkpoints are refused.
VENI_FORMAT_VERSION = 2


@dataclass(frozen=True)
class VeniConfig(StrictConfig):
    """Shapes of :class:`VeniVAE`. ``latent_dim`` is 3 x ``latent_vectors``."""

    #: (H, W) of the panoramas; W = 2 H.
    resolution: tuple[int, int] = (64, 128)
    #: N, the number of 3-vectors in the latent.
    latent_vectors: int = 43
    #: Decode radial depth as well (VENI+D); False: radiance only (VENI).
    depth: bool = False
    #: Vector channels of the encoder's tokens.
    channels: int = 48
    #: Invariant coordinates of each encoder channel (beside the 2 planar ones).
    invariants: int = 4
    #: Transformer blocks of the encoder.
    blocks: int = 3
    #: Attention heads (divide ``channels``).
    heads: int = 4
    #: Hidden width of the blocks' feed-forward layers, as a multiple of ``channels``.
    ff_mult: int = 2
    #: Width of the decoder's per-pixel MLP.
    field_width: int = 64
    #: Residual blocks of the decoder's MLP.
    field_blocks: int = 3
    #: Range the posterior log-variance is clamped to.
    logvar_range: tuple[float, float] = (-30.0, 20.0)

    def __post_init__(self) -> None:
        object.__setattr__(self, "resolution", tuple(int(v) for v in self.resolution))
        object.__setattr__(self, "logvar_range", tuple(float(v) for v in self.logvar_range))
        h, w = self.resolution
        if h <= 0 or w != 2 * h:
            raise RoomlightError(f"VeniConfig: resolution must satisfy W = 2 H, got {h}x{w}")
        for name in ("latent_vectors", "channels", "invariants", "blocks", "heads", "ff_mult", "field_width"):
            if getattr(self, name) <= 0:
                raise RoomlightError(f"VeniConfig: {name} must be positive, got {getattr(self, name)}")
        if self.channels % self.heads:
            raise RoomlightError(f"VeniConfig: heads={self.heads} must divide channels={self.channels}")
        if self.field_blocks < 0:
            raise RoomlightError(f"VeniConfig: field_blocks must be >= 0, got {self.field_blocks}")

    @property
    def latent_dim(self) -> int:
        """Length of the flattened latent, 3 N."""
        return 3 * self.latent_vectors

    @property
    def in_channels(self) -> int:
        """Data channels encoded and decoded: 3 (log1p RGB), 4 with depth."""
        return 4 if self.depth else 3


#: ``veni`` / ``veni-d``: 64 x 128, latent 129 = 43 vectors, next to the lite prior's 128. The bundled models
#: are these with ``--set model_overrides.latent_vectors=171`` (latent 513, next to the bundled prior's 512).
#: The ``-tiny`` ones are for tests (16 x 32).
VENI_PRESETS: dict[str, VeniConfig] = {
    "veni": VeniConfig(),
    "veni-d": VeniConfig(depth=True),
    "veni-tiny": VeniConfig(resolution=(16, 32), latent_vectors=4, channels=8, invariants=2, blocks=1, heads=2,
                            field_width=16, field_blocks=1),
    "veni-d-tiny": VeniConfig(resolution=(16, 32), latent_vectors=4, depth=True, channels=8, invariants=2,
                              blocks=1, heads=2, field_width=16, field_blocks=1),
}


def rotate_latent(z: torch.Tensor, angle: float) -> torch.Tensor:
    """z (..., 3N) with each vector (x, y, z) turned by ``angle`` about the up axis:
    (x + i z) -> (x + i z) e^{i angle}, y kept. A panorama rolled by k columns has angle 2πk/W."""
    v = z.unflatten(-1, (-1, 3))
    c, s = math.cos(angle), math.sin(angle)
    x, y, zz = v.unbind(-1)
    return torch.stack([x * c - zz * s, y, x * s + zz * c], -1).flatten(-2)


def _planar_first(directions: torch.Tensor) -> torch.Tensor:
    """(..., 3) world (x, y, z) -> (..., 3) ordered (x, z | y): planar part first."""
    return directions[..., [0, 2, 1]]


class VeniEncoder(nn.Module):
    """x (B, C, H, W) z-scored -> (mean (B, 3N), logvar (B, 3N)); see the module docstring."""

    def __init__(self, config: VeniConfig):
        super().__init__()
        self.config = c = config
        h, w = c.resolution
        # (W, H, 3): token j, channel i = pixel (i, j), coordinates (ω_x, ω_z, ω_y)
        self.register_buffer("directions", _planar_first(pixel_directions(h, w)).transpose(0, 1).contiguous(),
                             persistent=False)
        self.project = SO2Linear(h, 1 + c.in_channels, c.channels, c.invariants)
        self.cls = nn.Parameter(torch.zeros(c.channels, c.invariants))  # invariant part only: the planar one is 0
        self.blocks = nn.ModuleList(VNBlock(c.channels, c.heads, c.ff_mult) for _ in range(c.blocks))
        self.mean_head = SO2Linear(c.channels, c.invariants, c.latent_vectors, 1)
        self.logvar_head = SO2Linear(c.channels, c.invariants, c.latent_vectors, 1)

    def forward(self, x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        b = x.shape[0]
        data = x.permute(0, 3, 2, 1)                                           # (B, W, H, C)
        dirs = self.directions.expand(b, *self.directions.shape)
        tokens = self.project(torch.cat([dirs, data], -1))                      # (B, W, ch, 2 + inv)
        cls = torch.cat([torch.zeros_like(self.cls[:, :2]), self.cls], -1)      # (ch, 2 + inv)
        h = torch.cat([cls.expand(b, 1, *cls.shape), tokens], 1)               # (B, 1 + W, ch, 2 + inv)
        for block in self.blocks:
            h = block(h)
        head = h[:, 0]                                                          # (B, ch, 2 + inv)
        m = self.mean_head(head)                                                # (B, N, 3): (x, z | y)
        mean = m[..., [0, 2, 1]].flatten(1)                                     # (B, 3N): (x, y, z) per vector
        lv = self.logvar_head(head)
        logvar = torch.sqrt(lv[..., :2].square().sum(-1) + 1e-6) + lv[..., 2]  # (B, N): one per vector
        lo, hi = self.config.logvar_range
        return mean, logvar.clamp(lo, hi).repeat_interleave(3, dim=1)


class VeniField(nn.Module):
    """The conditional neural field: z (B, 3N), directions (P, 3) -> (B, P, C) z-scored values.

    Its first layer is linear in the invariants [<Z_i⊥, ω⊥>, Z_i⊥ × ω⊥, ω_y, |ω⊥|] of each pixel plus
    the image's [Z_iy], and is followed by a sine: the features are plane waves over the sphere
    whose directions and phases the latent sets. Written out, the inner products and cross products
    collapse to two per-image vectors a_x, a_z (B, width) with u = a_x ω_x + a_z ω_z + ..., so the first
    layer costs 4 multiply-adds per pixel and unit instead of 2N + 2.
    """

    #: Scale of the first layer's pre-activation: its sines start at a few cycles over the sphere.
    OMEGA = math.pi

    def __init__(self, config: VeniConfig):
        super().__init__()
        self.config = c = config
        n, width = c.latent_vectors, c.field_width
        self.dot = nn.Linear(n, width, bias=False)          # weights of <Z_i⊥, ω⊥>
        self.cross = nn.Linear(n, width, bias=False)        # weights of Z_i⊥ × ω⊥
        self.geo = nn.Linear(2, width)                      # ω_y, |ω⊥| and the bias
        self.cond = nn.ModuleList(nn.Linear(n, width) for _ in range(1 + c.field_blocks))
        self.norms = nn.ModuleList(nn.LayerNorm(width) for _ in range(c.field_blocks))
        self.hidden = nn.ModuleList(nn.Sequential(nn.Linear(width, width), nn.SiLU(), nn.Linear(width, width))
                                    for _ in range(c.field_blocks))
        self.out_norm = nn.LayerNorm(width)
        self.out = nn.Linear(width, c.in_channels)

    @staticmethod
    def invariants(z: torch.Tensor, directions: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """The field's inputs written out (slow; for tests): per pixel (B, P, 2N + 2) = [<Z_i⊥, ω⊥>,
        Z_i⊥ × ω⊥, ω_y, |ω⊥|] and per image (B, N) = [Z_iy]."""
        zx, zy, zz = z.unflatten(-1, (-1, 3)).unbind(-1)                                   # (B, N)
        dx, dy, dz = directions.unbind(-1)                                                   # (P,)
        dot = zx[:, None, :] * dx[None, :, None] + zz[:, None, :] * dz[None, :, None]
        cross = zx[:, None, :] * dz[None, :, None] - zz[:, None, :] * dx[None, :, None]
        b, p = z.shape[0], directions.shape[0]
        planar = torch.sqrt(dx.square() + dz.square())
        pixel = torch.cat([dot, cross, dy.expand(b, p)[..., None], planar.expand(b, p)[..., None]], -1)
        return pixel, zy

    @staticmethod
    def image_invariants(z: torch.Tensor) -> torch.Tensor:
        """(B, N) the per-image inputs [Z_iy].

        Only components linear in z. A norm |Z_i⊥| would be invariant too, but training decodes
        posterior samples, whose |Z_i⊥| is never near 0 where the posterior is wide, while the
        posterior mean (the encoder's reconstruction, the fits' start z = 0) puts it at 0: a field
        conditioned on it decoded means far worse than samples (docs/model.md)."""
        return z.unflatten(-1, (-1, 3))[..., 1]

    def first_layer(self, z: torch.Tensor, directions: torch.Tensor, image: torch.Tensor | None = None) -> torch.Tensor:
        """(B, P, width) pre-activation of the first layer, computed per image then per pixel (``image``:
        :meth:`image_invariants` of ``z``, when the caller has them already)."""
        zx, _, zz = z.unflatten(-1, (-1, 3)).unbind(-1)                                    # (B, N)
        a_x = self.dot(zx) - self.cross(zz)                                                  # (B, width)
        a_z = self.dot(zz) + self.cross(zx)
        dx, dy, dz = directions.unbind(-1)
        geo = self.geo(torch.stack([dy, torch.sqrt(dx.square() + dz.square())], -1))       # (P, width)
        image = self.image_invariants(z) if image is None else image
        return (a_x[:, None] * dx[None, :, None] + a_z[:, None] * dz[None, :, None] + geo[None]
                + self.cond[0](image)[:, None])

    def forward(self, z: torch.Tensor, directions: torch.Tensor, image: torch.Tensor | None = None) -> torch.Tensor:
        """(B, P, C); ``image``: the per-image inputs (B, N), :meth:`image_invariants` of ``z`` by default
        (scripts/mean_vs_sample.py takes them from another latent to find what a decoding depends on)."""
        image = self.image_invariants(z) if image is None else image                       # (B, N)
        h = torch.sin(self.OMEGA * self.first_layer(z, directions, image))
        for norm, mlp, cond in zip(self.norms, self.hidden, self.cond[1:]):
            h = h + mlp(norm(h)) + cond(image)[:, None]
        return self.out(self.out_norm(h))


class VeniVAE(SavedPrior, nn.Module):
    """VENI (radiance) or VENI+D (radiance + depth): the same interface as
    :class:`~roomlight.prior.model.panovae.PanoVAE` where the fitting and evaluation code use it.

    Args:
        config: shapes (:data:`VENI_PRESETS`).
        normalization: the statistics of (log1p RGB, log depth), as for the PanoVAE; VENI ignores
            the depth statistics.
        metadata: free-form JSON facts saved with the checkpoint.
    """

    FORMAT, FORMAT_VERSION, CONFIG_CLASS = VENI_FORMAT, VENI_FORMAT_VERSION, VeniConfig

    def __init__(self, config: VeniConfig | None = None, normalization: Normalization | None = None,
                 metadata: dict | None = None):
        super().__init__()
        self.config = config or VeniConfig()
        self.normalization = normalization
        self.metadata = {"depth_units": "metres", **(metadata or {})}
        self.encoder = VeniEncoder(self.config)
        self.field = VeniField(self.config)
        h, w = self.config.resolution
        self.register_buffer("directions", pixel_directions(h, w).reshape(-1, 3), persistent=False)
        self._weights_sha256: str | None = None

    # the photo view encoder exists for the PanoVAE only
    view_encoder = None

    def set_view_encoder(self, encoder) -> None:
        if encoder is not None:
            raise RoomlightError("VENI has no view encoder; fit it from the paper's start (--set init=samples)")

    @property
    def has_depth(self) -> bool:
        return self.config.depth

    # ------------------------------------------------------------------ normalised domain
    def encode_normalized(self, x: torch.Tensor) -> DiagonalGaussian:
        """x (B, 4 or 3, H, W) z-scored (a depth channel is ignored by VENI) -> posterior (B, 3N)."""
        h, w = self.config.resolution
        if x.dim() != 4 or x.shape[1] < self.config.in_channels or tuple(x.shape[-2:]) != (h, w):
            raise ShapeError(f"encode_normalized: expected (B, {self.config.in_channels}, {h}, {w}), "
                             f"got {tuple(x.shape)}")
        mean, logvar = self.encoder(x[:, :self.config.in_channels])
        return DiagonalGaussian(mean, logvar)

    def decode_normalized(self, z: torch.Tensor) -> torch.Tensor:
        """z (B, 3N) -> (B, C, H, W) z-scored, C = 3 or 4."""
        if z.dim() != 2 or z.shape[1] != self.config.latent_dim:
            raise ShapeError(f"decode: expected z of shape (B, {self.config.latent_dim}), got {tuple(z.shape)}")
        h, w = self.config.resolution
        out = self.field(z, self.directions)                                    # (B, H W, C)
        return out.transpose(1, 2).reshape(z.shape[0], -1, h, w)

    def forward_normalized(self, x: torch.Tensor, sample: bool | None = None,
                           generator: torch.Generator | None = None) -> tuple[torch.Tensor, DiagonalGaussian]:
        """Reconstruct x (B, 4, H, W): (x_hat (B, 4, H, W), posterior). VENI passes the input's depth
        channel through unchanged, so the training objective's depth terms are zero for it."""
        posterior = self.encode_normalized(x)
        x_hat = self.decode_normalized(self._posterior_latent(posterior, sample, generator))
        if not self.has_depth:
            x_hat = torch.cat([x_hat, x[:, 3:4].detach()], 1)
        return x_hat, posterior

    forward = forward_normalized

    # ------------------------------------------------------------------ physical domain
    def encode(self, radiance: torch.Tensor, depth: torch.Tensor | None = None) -> DiagonalGaussian:
        """Posterior for radiance (B, 3, H, W) and depth (B, 1, H, W) in metres (VENI: depth may be None)."""
        if depth is None:
            if self.has_depth:
                raise RoomlightError("VENI+D encodes radiance and depth; pass the depth")
            depth = torch.ones_like(radiance[:, :1])
        return self.encode_normalized(self._require_normalization().normalize(radiance, depth))

    def decode(self, z: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor | None]:
        """z (B, 3N) -> (radiance (B, 3, H, W), depth (B, 1, H, W) in metres, or None for VENI)."""
        x = self.decode_normalized(z)
        if not self.has_depth:
            x = torch.cat([x, torch.zeros_like(x[:, :1])], 1)
        radiance, depth = self._require_normalization().denormalize(x)
        return radiance, depth if self.has_depth else None

    # ------------------------------------------------------------------ checkpoints
    # save_pretrained comes from SavedPrior (format roomlight.veni)

    @classmethod
    def from_pretrained(cls, path: str | Path, device: str | torch.device = "cpu") -> "VeniVAE":
        """Load a folder written by :meth:`save_pretrained` (or a file inside it); eval mode."""
        path = Path(path)
        directory = path if path.is_dir() else path.parent
        if not (directory / CONFIG_NAME).is_file() or not (directory / WEIGHTS_NAME).is_file():
            raise InputFileError(directory, f"not a VENI checkpoint: expected {CONFIG_NAME} + {WEIGHTS_NAME}")
        version = checkpoint_format_version(directory)
        if version is not None and version < VENI_FORMAT_VERSION:
            raise InputFileError(directory, f"a VENI checkpoint of format_version {version}, whose decoder also "
                                 f"took |Z_i⊥| (see docs/model.md, VENI); this roomlight reads version "
                                 f"{VENI_FORMAT_VERSION}: retrain it with `roomlight train --config veni` / `veni-d`")
        return cls._load_saved(directory).to(device).eval()
