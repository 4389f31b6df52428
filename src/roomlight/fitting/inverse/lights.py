"""What an illumination fit optimises: the prior's latent, or free per-pixel maps.

Each light model turns its parameters into (radiance (H, W, 3), depth (H, W) or None) and the
emitter kind that shows them (``mesh``, ``envmap`` or ``sphere:R``), plus its own
regularisers. The fitting loop (:mod:`roomlight.fitting.inverse.fitter`) does not know which it drives.

- :class:`PriorLight`: z in R^latent (init 0) and log-exposure s (init log 0.18), decoded by
  a frozen PanoVAE decoder; shown as the 2.5D area light (``prior``) or at infinity
  (``prior-envmap``). Optionally a white balance c beside the exposure (per-channel gain
  exp(s + c), sum c = 0, a weak pull to neutral), a Gaussian prior on z, a fitted global depth
  scale and a floor under the depth that keeps given points inside the light.
- :class:`DirectLight`: free log-radiance (and, for the 2.5D light, log-depth) maps at
  128 x 256 with the smoothness prior (the paper's "Smoothness" baselines).
"""

from __future__ import annotations

import math

import torch

from roomlight.fitting.inverse.floor import apply_floor
from roomlight.fitting.inverse.smoothness import smoothness

__all__ = ["LightModel", "PriorLight", "DirectLight"]


class LightModel(torch.nn.Module):
    """Base class: parameters -> emitter maps."""

    kind: str = "mesh"

    @property
    def resolution(self) -> tuple[int, int]:
        raise NotImplementedError

    @property
    def has_depth(self) -> bool:
        """True when the emitter's geometry is optimised (the repulsion term applies)."""
        return self.kind == "mesh"

    def emitter(self) -> tuple[torch.Tensor, torch.Tensor | None]:
        """(radiance (H, W, 3) linear, depth (H, W) metres or None)."""
        raise NotImplementedError

    def regularizers(self) -> dict[str, torch.Tensor]:
        """Named weighted regularisation terms added to the objective."""
        return {}

    def describe(self) -> dict:
        """JSON-friendly summary of the current parameters (logged per iteration)."""
        return {}

    def scene_values(self) -> dict[str, torch.Tensor]:
        """Further scene parameters this model drives, by their ``mi.traverse`` key (e.g. the
        materials of the objects, fitted jointly with the light); written into the scene with
        every render. None by default."""
        return {}


class PriorLight(LightModel):
    """The paper's method: optimise (z, s) through a frozen decoder.

    Args:
        model: the prior (a PanoVAE; frozen here).
        envmap: show the radiance at infinity (``prior-envmap``) instead of as the 2.5D light.
        init_exposure: e^s at the start.
        z_prior: weight of 0.5 |z|^2.
        z_anchor: weight of 0.5 |z - z_start|^2, a pull towards where the fit started (see
            :meth:`anchor_here`); 0 = off.
        fit_depth_scale: also fit a global log scale of the decoded depth.
        white_balance: weight w of the pull to neutral of a white balance c in R^3 fitted beside
            the exposure, or None for the paper's scalar exposure. The radiance is multiplied by
            the per-channel gain exp(s + c) with c centred (sum c = 0, so s alone sets the level)
            and the regulariser w |c|^2 added: the light's colour can follow the observations
            without the latent moving the room's layout to change it.
    """

    def __init__(self, model, envmap: bool = False, init_exposure: float = 0.18, z_prior: float = 0.0,
                 fit_depth_scale: bool = False, white_balance: float | None = None, z_anchor: float = 0.0):
        super().__init__()
        self.model = model.eval()
        for p in self.model.parameters():
            p.requires_grad_(False)
        self.kind = "envmap" if envmap else "mesh"
        latent = model.config.latent_dim
        self.z = torch.nn.Parameter(torch.zeros(latent))
        self.s = torch.nn.Parameter(torch.tensor(math.log(init_exposure)))
        self.log_depth_scale = torch.nn.Parameter(torch.zeros(())) if fit_depth_scale else None
        if white_balance is not None and not white_balance >= 0:
            raise ValueError(f"white_balance weight must be >= 0 or None, got {white_balance}")
        #: raw white balance (3,); only its centred part acts (:meth:`log_white_balance`)
        self.c = torch.nn.Parameter(torch.zeros(3)) if white_balance is not None else None
        self.white_balance = white_balance
        self.z_prior = z_prior
        if not z_anchor >= 0:
            raise ValueError(f"z_anchor weight must be >= 0, got {z_anchor}")
        self.z_anchor = z_anchor
        #: (latent,) where the anchor term pulls z; zeros until :meth:`anchor_here`. A buffer, so it
        #: follows the light to its device; a resumed fit sets it again from the same start.
        self.register_buffer("z_start", torch.zeros(latent))
        self._anchored = False
        #: (H, W) floor under the decoded depth (:mod:`roomlight.fitting.inverse.floor`), or None. A plain
        #: attribute, not a buffer: it belongs to the fit's scene, not to the light's state.
        self.depth_floor: torch.Tensor | None = None

    @property
    def resolution(self) -> tuple[int, int]:
        return tuple(self.model.config.resolution)

    def log_white_balance(self) -> torch.Tensor | None:
        """c - mean(c): (3,) log per-channel gains summing to 0, or None without a white balance."""
        return None if self.c is None else self.c - self.c.mean()

    def log_gain(self) -> torch.Tensor:
        """(3,) log of the per-channel gain applied to the decoded radiance: s (+ c)."""
        c = self.log_white_balance()
        return self.s.expand(3) if c is None else self.s + c

    def emitter(self):
        rad, depth = self.model.decode(self.z[None])
        rad = rad[0].permute(1, 2, 0) * torch.exp(self.log_gain())
        if self.kind == "envmap":
            return rad, None
        d = depth[0, 0]
        if self.log_depth_scale is not None:
            d = d * torch.exp(self.log_depth_scale)
        return rad, apply_floor(d, self.depth_floor)

    def anchor_here(self) -> None:
        """Make the current z the point the anchor term pulls towards (call after setting the start)."""
        with torch.no_grad():
            self.z_start.copy_(self.z)
        self._anchored = True

    def regularizers(self):
        terms = {}
        if self.z_prior > 0:
            terms["z_prior"] = self.z_prior * 0.5 * self.z.square().sum()
        if self.z_anchor > 0:
            terms["z_anchor"] = self.z_anchor * 0.5 * (self.z - self.z_start).square().sum()
        c = self.log_white_balance()
        if c is not None and self.white_balance > 0:
            terms["white_balance"] = self.white_balance * c.square().sum()
        return terms

    def describe(self):
        d = {"exposure": float(torch.exp(self.s.detach())), "z_norm": float(self.z.detach().norm())}
        if self._anchored:
            # How far the fit moved the room from its start: what the anchor term holds back.
            d["z_travel"] = float((self.z.detach() - self.z_start).norm())
        c = self.log_white_balance()
        if c is not None:
            d["white_balance"] = [round(float(v), 6) for v in torch.exp(c.detach())]
            d["gain"] = [float(v) for v in torch.exp(self.log_gain().detach())]
        if self.log_depth_scale is not None:
            d["depth_scale"] = float(torch.exp(self.log_depth_scale.detach()))
        return d


def _log_map(value, shape, floor: float) -> torch.Tensor:
    """log of a constant or a map of the given shape (clamped at ``floor`` so log stays finite)."""
    if isinstance(value, torch.Tensor):
        if tuple(value.shape) != tuple(shape):
            from roomlight.errors import ShapeError

            raise ShapeError(f"direct light: initial map has shape {tuple(value.shape)}, expected {tuple(shape)}")
        return torch.log(value.detach().float().clamp(min=floor)).clone()
    return torch.full(shape, math.log(max(float(value), floor)))


class DirectLight(LightModel):
    """Free per-pixel log radiance (and log depth for the 2.5D light) with smoothness priors.

    Args:
        kind: ``mesh`` (2.5D area light, depth optimised too), ``envmap``, or ``sphere:R``.
        resolution: (H, W) of the maps.
        init_radiance: the radiance at the start: a constant, or an (H, W, 3) map (> 0).
        init_depth: the depth at the start (``mesh`` only), metres: a constant or an (H, W) map.
        smooth_radiance, smooth_depth: weights of the smoothness terms on log radiance / log depth.
    """

    def __init__(self, kind: str, resolution=(128, 256), init_radiance=0.18, init_depth=2.0,
                 smooth_radiance: float = 5e-5, smooth_depth: float = 1e-4):
        super().__init__()
        self.kind = kind
        h, w = resolution
        self._resolution = (h, w)
        self.log_radiance = torch.nn.Parameter(_log_map(init_radiance, (h, w, 3), 1e-6))
        self.log_depth = torch.nn.Parameter(_log_map(init_depth, (h, w), 1e-3)) if kind == "mesh" else None
        self.smooth_radiance = smooth_radiance
        self.smooth_depth = smooth_depth

    @property
    def resolution(self):
        return self._resolution

    def emitter(self):
        rad = torch.exp(self.log_radiance)
        return rad, (torch.exp(self.log_depth) if self.log_depth is not None else None)

    def regularizers(self):
        terms = {"smooth_radiance": self.smooth_radiance * smoothness(self.log_radiance)}
        if self.log_depth is not None:
            terms["smooth_depth"] = self.smooth_depth * smoothness(self.log_depth)
        return terms

    def describe(self):
        d = {"mean_log_radiance": float(self.log_radiance.detach().mean())}
        if self.log_depth is not None:
            d["mean_depth"] = float(torch.exp(self.log_depth.detach()).mean())
        return d
