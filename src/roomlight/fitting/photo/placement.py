"""Where a photo fit starts: a large room from the prior, the scene placed inside it, an exposure.

The prior's mean room (z = 0) is small, so, as in the paper, the fit starts from a sample of
N(0, I) with large geometry: ``init_samples`` latents are drawn and the one whose decoded depth
has the largest median is kept. The photographed scene (the camera and every point the depth
map shows) is then scaled and translated inside that room: the scale s and translation t of
p_room = t + s R p_camera minimise

    mean over frustum pixels (log D(q / |q|) - log |q|)^2  +  lambda_rep * mean_q' max(m - g(q'), 0)

(the frustum depth term and the repulsion of the objects' and free-space points, the same terms
as the fit's), starting from t = 0 and the median ratio of the room's depth to the photograph's.
The exposure then makes the emitter's log-average luminance over the observed directions equal
to the photograph's.
"""

from __future__ import annotations

import math

import numpy as np
import torch

from roomlight.core.color import LOG_EPS, luminance_np
from roomlight.core.geometry.equirect import sample_equirect
from roomlight.fitting.inverse.repulsion import repulsion_penalty
from roomlight.fitting.photo.geometry import SceneTransform

__all__ = ["initial_latent", "place_scene", "matching_log_exposure"]


@torch.no_grad()
def initial_latent(model, samples: int, seed: int = 0) -> tuple[torch.Tensor, list[float]]:
    """The N(0, I) latent (D,) with the largest median decoded depth among ``samples`` draws, and
    every draw's median depth (metres)."""
    g = torch.Generator().manual_seed(int(seed))
    z = torch.randn(samples, model.config.latent_dim, generator=g)
    device = next(model.parameters()).device
    medians = []
    for chunk in z.split(8):
        _, depth = model.decode(chunk.to(device))
        medians.extend(depth.flatten(1).median(1).values.cpu().tolist())
    return z[int(np.argmax(medians))].clone(), medians


def place_scene(depth: torch.Tensor, rotation: np.ndarray, observed: np.ndarray, repelled: np.ndarray,
                margin: float, lambda_rep: float = 1.0, steps: int = 200, lr: float = 0.05) -> SceneTransform:
    """Scale and translate the photographed scene inside the room of ``depth`` (module docstring).

    Args:
        depth: (H, W) the room's radial depth map, metres.
        rotation: (3, 3) camera-to-room rotation (kept fixed).
        observed: (N, 3) camera-frame points the unmasked pixels see.
        repelled: (M, 3) camera-frame points that must stay inside the room by ``margin``.
    """
    d = depth.detach().float().cpu()
    R = torch.as_tensor(rotation, dtype=torch.float32)
    obs = torch.as_tensor(observed, dtype=torch.float32) @ R.T
    rep = torch.as_tensor(repelled, dtype=torch.float32) @ R.T
    if len(obs):
        ratio = sample_equirect(d[None, None], obs)[0, 0] / obs.norm(dim=-1).clamp_min(1e-6)
        scale0 = float(ratio.median())
    else:  # no background seen: fit the objects' extent into the room instead
        ratio = sample_equirect(d[None, None], rep)[0, 0] / rep.norm(dim=-1).clamp_min(1e-6)
        scale0 = 0.5 * float(ratio[torch.isfinite(ratio)].median())
    log_scale = torch.tensor(math.log(max(scale0, 1e-3)), requires_grad=True)
    shift = torch.zeros(3, requires_grad=True)
    opt = torch.optim.Adam([log_scale, shift], lr=lr)

    def objective():
        s = torch.exp(log_scale)
        loss = repulsion_penalty(d, shift + s * rep, margin) * lambda_rep
        if len(obs):
            q = shift + s * obs
            dq = sample_equirect(d[None, None], q)[0, 0]
            loss = loss + (torch.log(dq.clamp_min(1e-6)) - torch.log(q.norm(dim=-1).clamp_min(1e-6))).square().mean()
        return loss

    for _ in range(steps):
        opt.zero_grad()
        objective().backward()
        opt.step()
    return SceneTransform(rotation, float(torch.exp(log_scale.detach())), shift.detach().double().numpy())


def _unsaturated_pairs(radiance: torch.Tensor, directions, observed, tau: float):
    """(observed (M, 3), emitted (M, 3)) float64 radiance of the unsaturated observations and of the
    emitter (H, W, 3) sampled in their directions (N, 3), or None when every observation is saturated."""
    obs = torch.as_tensor(observed, dtype=torch.float32)
    dirs = torch.as_tensor(directions, dtype=torch.float32)
    keep = obs.amax(-1) < tau
    if not bool(keep.any()):
        return None
    emitted = sample_equirect(radiance.detach().float().cpu().permute(2, 0, 1)[None], dirs[keep])[0].T
    return obs[keep].numpy().astype(np.float64), emitted.numpy().astype(np.float64)


def matching_log_exposure(radiance: torch.Tensor, directions, observed, tau: float = 0.99) -> float:
    """log of the factor that gives the emitter (H, W, 3) radiance, sampled in ``directions`` (N, 3),
    the log-average luminance of the observed (N, 3) radiance; saturated observations are left out.
    0 when nothing is observed."""
    pair = _unsaturated_pairs(radiance, directions, observed, tau)
    if pair is None:
        return 0.0
    y_obs, y_em = luminance_np(pair[0]), luminance_np(pair[1])
    return float(np.log(y_obs + LOG_EPS).mean() - np.log(y_em + LOG_EPS).mean())


#: Largest |c_k| of a starting white balance: a factor of e^0.5 = 1.65 between a channel and the mean.
MAX_START_WHITE_BALANCE = 0.5


def matching_white_balance(radiance: torch.Tensor, directions, observed, tau: float = 0.99) -> np.ndarray:
    """(3,) centred log gains that give the emitter (H, W, 3), sampled in ``directions`` (N, 3), the
    colour of the observed (N, 3) radiance there: per channel, log-average observed minus
    log-average emitted, minus their mean (so the level stays the exposure's), clipped to
    +-:data:`MAX_START_WHITE_BALANCE`. Zeros when nothing unsaturated is observed."""
    pair = _unsaturated_pairs(radiance, directions, observed, tau)
    if pair is None:
        return np.zeros(3)
    o = np.log(pair[0] + LOG_EPS).mean(0)
    e = np.log(pair[1] + LOG_EPS).mean(0)
    c = (o - e) - (o - e).mean()
    return np.clip(c, -MAX_START_WHITE_BALANCE, MAX_START_WHITE_BALANCE)
