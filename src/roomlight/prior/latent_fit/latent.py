"""Fitting the prior's latent to a panorama (supp. "Fitting details", VENI's protocol).

The decoder is frozen; z (init 0) is optimised with Adam to minimise the squared error between
the decoded and the target panorama in the network's normalised space (z-scored log1p RGB and
log depth), with the learning rate decayed exponentially from 0.1 to 0.01 over 1500 steps.
Targets can be radiance + depth (the paper's protocol: depth is one channel of four, so it gets a
quarter of the objective), radiance only (panoramas without depth) or depth only.

Beyond the protocol, the objective can weigh the depth channel more (``depth_weight``) and add the
training loss's peak term per panorama (``peak_weight``), and z can start from the encoder's
posterior mean (``init_from_encoder``): in the squared error of normalised channels, depth and the
few pixels of the light sources weigh little, and a fit from z = 0 trades them for radiance.

Each panorama of a batch has its own latent; the objective is the sum over the batch of each
panorama's mean squared error, so a panorama's fit does not depend on what else is in the batch.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import torch

from roomlight.core.config import StrictConfig
from roomlight.errors import RoomlightError, ShapeError
from roomlight.prior.losses.peak import peak_loss_per_sample

__all__ = ["LatentFitConfig", "LatentFitResult", "fit_latent", "TARGETS", "FitProblem", "fit_problem", "optimise"]

#: Which normalised channels enter the objective.
TARGETS = {"both": (0, 1, 2, 3), "radiance": (0, 1, 2), "depth": (3,)}


@dataclass(frozen=True)
class LatentFitConfig(StrictConfig):
    """Settings of :func:`fit_latent` (defaults: the paper's protocol)."""

    #: Adam iterations.
    steps: int = 1500
    #: Initial learning rate.
    lr: float = 0.1
    #: Learning rate after ``steps`` iterations (exponential decay in between).
    lr_final: float = 0.01
    #: Adam (beta1, beta2); torch's defaults, as the protocol names plain Adam.
    betas: tuple[float, float] = (0.9, 0.999)
    #: Channels fitted: ``both`` (radiance + depth), ``radiance`` or ``depth``.
    target: str = "both"
    #: Start from the encoder's posterior mean instead of z = 0 (needs radiance and depth).
    init_from_encoder: bool = False
    #: Weight of the depth channel against each radiance channel in the squared error (1: the
    #: paper's protocol, where depth is one channel of four; no effect unless depth is fitted).
    depth_weight: float = 1.0
    #: Weight of a peak term added to the objective: the log-L1 error of linear radiance over the
    #: brightest ``peak_fraction`` of pixels of the target and of the decoded panorama (the
    #: training loss's peak term, per panorama). 0: the paper's protocol.
    peak_weight: float = 0.0
    #: Share of pixels taken as peaks by the peak term.
    peak_fraction: float = 0.005
    #: Record the loss every this many steps in :attr:`LatentFitResult.history`.
    history_every: int = 10

    def __post_init__(self) -> None:
        object.__setattr__(self, "betas", tuple(float(b) for b in self.betas))
        if self.target not in TARGETS:
            raise RoomlightError(f"LatentFitConfig.target = {self.target!r}: use one of {sorted(TARGETS)}")
        if self.steps < 0 or self.lr <= 0 or self.lr_final <= 0:
            raise RoomlightError("LatentFitConfig: steps must be >= 0 and learning rates > 0")
        if self.depth_weight < 0 or self.peak_weight < 0:
            raise RoomlightError("LatentFitConfig: depth_weight and peak_weight must be >= 0")
        if not 0.0 < self.peak_fraction <= 1.0:
            raise RoomlightError(f"LatentFitConfig.peak_fraction = {self.peak_fraction}: use a share in (0, 1]")
        if self.target == "depth" and self.peak_weight > 0:
            raise RoomlightError("LatentFitConfig: the peak term needs radiance (target 'both' or 'radiance')")

    def describe(self) -> str:
        """One sentence naming the optimiser, the start and the objective (for reports)."""
        start = "the encoder's mean" if self.init_from_encoder else "z = 0"
        objective = "squared error of the normalised channels"
        if self.depth_weight != 1.0:
            objective += f", depth weighted {self.depth_weight:g}×"
        if self.peak_weight > 0:
            objective += (f", + {self.peak_weight:g} × log-L1 over the brightest "
                          f"{100 * self.peak_fraction:g} % of pixels")
        if self.is_paper_protocol:
            objective += " (the paper's protocol)"
        return (f"Adam, {self.steps} steps, lr {self.lr:g} → {self.lr_final:g} (exponential), from {start}; "
                f"{objective}")

    @property
    def is_paper_protocol(self) -> bool:
        """True for the paper's start and objective: z = 0, plain squared error of the normalised channels."""
        return not self.init_from_encoder and self.depth_weight == 1.0 and self.peak_weight == 0.0


@dataclass
class LatentFitResult:
    """Outcome of :func:`fit_latent`.

    Attributes:
        z: (B, latent_dim) the best latents found (lowest per-panorama objective).
        loss: (B,) their objective values (mean squared error over the fitted channels).
        radiance: (B, 3, H, W) decoded linear radiance at ``z``.
        depth: (B, 1, H, W) decoded depth at ``z`` (units of the model's data, e.g. metres).
        history: list of (step, mean loss over the batch).
    """

    z: torch.Tensor
    loss: torch.Tensor
    radiance: torch.Tensor
    depth: torch.Tensor
    history: list = field(default_factory=list)


def _check_inputs(model, radiance, depth, target):
    h, w = model.config.resolution
    if radiance is not None and (radiance.dim() != 4 or radiance.shape[1:] != (3, h, w)):
        raise ShapeError(f"fit_latent: radiance must be (B, 3, {h}, {w}), got {tuple(radiance.shape)} "
                         f"(resample to the model's resolution first)")
    if depth is not None and (depth.dim() != 4 or depth.shape[1:] != (1, h, w)):
        raise ShapeError(f"fit_latent: depth must be (B, 1, {h}, {w}), got {tuple(depth.shape)}")
    if target in ("both", "radiance") and radiance is None:
        raise RoomlightError(f"fit_latent: target {target!r} needs radiance")
    if target != "radiance" and not getattr(model, "has_depth", True):
        raise RoomlightError(f"fit_latent: target {target!r} needs a model that decodes depth; this one "
                             "(VENI) decodes radiance only: fit target 'radiance'")
    if target in ("both", "depth") and depth is None:
        raise RoomlightError(f"fit_latent: target {target!r} needs depth (use target='radiance' for "
                             "panoramas without depth)")


def _channel_weights(config: LatentFitConfig, channels: list[int], device) -> torch.Tensor:
    """(C,) weights of the fitted channels, summing to 1 (equal weights: a plain mean)."""
    w = torch.tensor([config.depth_weight if c == 3 else 1.0 for c in channels], device=device)
    if float(w.sum()) <= 0:
        raise RoomlightError("LatentFitConfig: every fitted channel has weight 0")
    return w / w.sum()


def fit_latent(model, radiance: torch.Tensor | None, depth: torch.Tensor | None,
               config: LatentFitConfig = LatentFitConfig(), z0: torch.Tensor | None = None, callback=None) -> LatentFitResult:
    """Optimise one latent per panorama so that the decoder reproduces it.

    Args:
        model: a :class:`~roomlight.prior.model.PanoVAE` with normalisation statistics (left in eval
            mode; its weights get no gradient).
        radiance: (B, 3, H, W) linear radiance at the model's resolution, exposure calibrated like
            its training data; None for ``target='depth'``.
        depth: (B, 1, H, W) radial depth in the model's units; None for ``target='radiance'``.
        config: optimisation settings.
        z0: (B, latent_dim) initial latents (default zeros, or the encoder's mean with
            ``config.init_from_encoder``).
        callback: called as ``callback(step, mean_loss)`` after every step (e.g. a progress bar).
    Returns:
        :class:`LatentFitResult` with the best iterate per panorama.
    """
    _check_inputs(model, radiance, depth, config.target)
    norm = model.normalization
    if norm is None:
        raise RoomlightError("fit_latent: the model has no normalisation statistics")
    problem = fit_problem(norm, model.config.resolution, radiance, depth, config)
    was_training = model.training
    # Freeze the decoder for the fit, and give every parameter back the flag it had: a model
    # that is partly frozen (or being trained elsewhere) must come back exactly as it was.
    params = list(model.parameters())
    required = [p.requires_grad for p in params]
    model.eval()
    for p in params:
        p.requires_grad_(False)
    try:
        if z0 is None and config.init_from_encoder:
            if radiance is None or depth is None:
                raise RoomlightError("fit_latent: init_from_encoder needs both radiance and depth")
            with torch.no_grad():
                z0 = model.encode(problem.radiance, problem.depth).mean
        b = problem.x.shape[0]
        z = z0.detach().clone() if z0 is not None else torch.zeros(b, model.config.latent_dim, device=problem.x.device)
        best_z, best_loss, history = optimise(z.float(), model.decode_normalized, problem, config, callback)
        with torch.no_grad():
            out_rad, out_dep = model.decode(best_z)
    finally:
        for p, flag in zip(params, required):
            p.requires_grad_(flag)
        model.train(was_training)
    return LatentFitResult(best_z, best_loss, out_rad, out_dep, history)


@dataclass
class FitProblem:
    """What a fit reproduces, in the network's normalised space.

    Attributes:
        x: (B, C, H, W) the fitted channels of the normalised target.
        channels: which of the four normalised channels ``x`` holds.
        weights: (1, C) their weights, summing to 1.
        radiance, depth: (B, 3, H, W), (B, 1, H, W) the targets (placeholders of 1 where missing).
        peak_target: (B, 3, H, W) the radiance the peak term ranks, or None without a peak term.
        normalization: the statistics, to reach linear radiance for the peak term.
    """

    x: torch.Tensor
    channels: list
    weights: torch.Tensor
    radiance: torch.Tensor
    depth: torch.Tensor
    peak_target: torch.Tensor | None
    normalization: object


def fit_problem(norm, resolution, radiance, depth, config: LatentFitConfig) -> FitProblem:
    """The :class:`FitProblem` of ``radiance`` / ``depth`` under ``config`` (target channels, weights)."""
    ref = radiance if radiance is not None else depth
    b, device = ref.shape[0], ref.device
    h, w = resolution
    # Missing channels get placeholders (excluded from the objective) so that normalize() applies.
    rad = (radiance if radiance is not None else torch.ones(b, 3, h, w, device=device)).float()
    dep = (depth if depth is not None else torch.ones(b, 1, h, w, device=device)).float()
    channels = list(TARGETS[config.target])
    weights = _channel_weights(config, channels, device).view(1, -1)  # (1, C)
    with torch.no_grad():
        x = norm.normalize(rad, dep)[:, channels]
        # Decoded radiance is never negative (denormalize clamps it), so the target's negative
        # values are clamped too before the peak term ranks its brightest pixels.
        peak = rad.clamp_min(0.0) if config.peak_weight > 0 else None
    return FitProblem(x, channels, weights, rad, dep, peak, norm)


def optimise(params: torch.Tensor, decode, problem: FitProblem, config: LatentFitConfig, callback=None,
             regularizer=None) -> tuple[torch.Tensor, torch.Tensor, list]:
    """Adam on ``params`` (B, ...) so that ``decode(params)`` (B, >= C, H, W normalised) reproduces the
    problem; each panorama's objective is the weighted mean squared error of its channels (+ the peak
    term, + ``regularizer(params)`` (B,) if given). Returns (best params, their objective (B,), history)."""
    p = params.detach().clone().requires_grad_(True)
    opt = torch.optim.Adam([p], lr=config.lr, betas=config.betas)
    gamma = (config.lr_final / config.lr) ** (1.0 / max(config.steps, 1))
    sched = torch.optim.lr_scheduler.ExponentialLR(opt, gamma)
    b = p.shape[0]
    best_p, best_loss = p.detach().clone(), torch.full((b,), math.inf, device=p.device)
    history = []
    for step in range(config.steps + 1):
        x_full = decode(p)  # (B, 4, H, W); a radiance-only decoder gives (B, 3, H, W)
        per = ((x_full[:, problem.channels] - problem.x).pow(2).mean((2, 3)) * problem.weights).sum(1)  # (B,)
        if problem.peak_target is not None:
            if x_full.shape[1] == 3:
                x_full = torch.cat([x_full, torch.zeros_like(x_full[:, :1])], 1)
            per = per + config.peak_weight * peak_loss_per_sample(problem.normalization.denormalize(x_full)[0],
                                                                  problem.peak_target, config.peak_fraction)
        if regularizer is not None:
            per = per + regularizer(p)
        with torch.no_grad():
            better = per < best_loss
            best_loss = torch.where(better, per.detach(), best_loss)
            best_p[better] = p.detach()[better]
        if step % config.history_every == 0 or step == config.steps:
            history.append((step, float(per.detach().mean())))
        if step == config.steps:
            break  # the last evaluation only scores the final iterate
        opt.zero_grad(set_to_none=True)
        per.sum().backward()
        opt.step()
        sched.step()
        if callback is not None:
            callback(step + 1, float(per.detach().mean()))
    return best_p, best_loss, history
