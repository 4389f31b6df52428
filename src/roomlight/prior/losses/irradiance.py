"""Irradiance at the capture point: what a panorama delivers to surfaces, compared in log.

The prior's reconstruction losses compare pixels in a log-like domain (z-scored ``log1p``), and
the peak loss compares the brightest pixels in log. Where a panorama's emitters are uncertain
(a view encoder guessing the part of the room a photograph does not show) a per-pixel log loss
is minimised by a smeared, dim lamp: the mean of log radiance over possible lamp positions is far
below the log of its mean, so the energy the guess delivers drops with its uncertainty. The
irradiance, a cosine-weighted integral over half the sphere, hardly depends on where exactly a lamp
is, and is what lights a diffuse object; comparing it in log keeps the guess's energy honest
without asking for a position the view cannot tell.

    E_c(n) = sum_pixels L_c(w) max(0, n . w) dOmega(w)                      (radiance x sr)
    L_irr  = mean_{b, n, c} | log(E^_c(n) + eps) - log(E_c(n) + eps) |

over a fixed set of normals n (the 6 axis directions and the 8 cube diagonals), with the equirect
pixels' exact solid angles.

A photo fit never sees the guess's absolute level: its start is scaled so that the part of the
light the photograph shows has the photograph's log-average luminance
(:func:`roomlight.fitting.photo.placement.matching_log_exposure`). Given the ``seen`` cells, the
guess is scaled the same way before its irradiance is compared (:func:`seen_matched`): the loss then
asks only for the unseen room's energy *relative to the seen part*, which is what reaches the
fit's light, and no longer rewards brightening the whole room, seen walls included.
"""

from __future__ import annotations

import math
from functools import lru_cache

import torch

from roomlight.core.geometry.equirect import pixel_directions, pixel_solid_angles
from roomlight.errors import ShapeError
from roomlight.prior.losses.l1 import check_same_shape

__all__ = ["IRRADIANCE_NORMALS", "irradiance_weights", "irradiance_at_centre", "irradiance_loss",
           "irradiance_log_ratio", "seen_matched"]


def _normals() -> torch.Tensor:
    axes = torch.eye(3, dtype=torch.float64)
    axes = torch.cat([axes, -axes])
    diag = torch.tensor([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=torch.float64)
    return torch.cat([axes, diag / math.sqrt(3.0)])


#: (14, 3) unit normals: the six axis directions and the eight cube diagonals (float64).
IRRADIANCE_NORMALS = _normals()


@lru_cache(maxsize=8)
def _cached_weights(height: int, width: int) -> torch.Tensor:
    dirs = pixel_directions(height, width, dtype=torch.float64).reshape(-1, 3)  # (HW, 3)
    omega = pixel_solid_angles(height, width, dtype=torch.float64).reshape(-1)  # (HW,)
    return (IRRADIANCE_NORMALS @ dirs.T).clamp_min(0.0) * omega  # (N, HW)


def irradiance_weights(height: int, width: int, dtype=torch.float32, device=None) -> torch.Tensor:
    """(N, H*W) weights max(0, n . w) dOmega(w) of each pixel for each of :data:`IRRADIANCE_NORMALS`."""
    return _cached_weights(height, width).to(dtype=dtype, device=device)


def irradiance_at_centre(radiance: torch.Tensor) -> torch.Tensor:
    """Irradiance at the panorama's centre on surfaces facing each of :data:`IRRADIANCE_NORMALS`.

    Args:
        radiance: (B, 3, H, W) linear radiance of an equirect panorama (negative values count as 0).
    Returns:
        (B, N, 3) irradiance, radiance units times steradians (a constant panorama L gives pi L).
    """
    if radiance.dim() != 4 or radiance.shape[1] != 3:
        raise ShapeError(f"irradiance_at_centre: expected (B, 3, H, W) linear radiance, got {tuple(radiance.shape)}")
    b, _, h, w = radiance.shape
    weights = irradiance_weights(h, w, dtype=radiance.dtype, device=radiance.device)
    return torch.einsum("nk,bck->bnc", weights, radiance.clamp_min(0.0).reshape(b, 3, h * w))


def seen_matched(pred: torch.Tensor, target: torch.Tensor, seen: torch.Tensor) -> torch.Tensor:
    """``pred`` scaled, per panorama, so that its ``seen`` cells have ``target``'s log-average luminance.

    The log-average is weighted by the cells' solid angles (a photograph's pixels cover about equal
    solid angles) and taken over the Rec.709 luminance plus :data:`~roomlight.core.color.LOG_EPS`, as the
    photo fit's exposure match takes it. The factor is differentiable in ``pred``, so a loss on the
    result cannot be lowered by scaling ``pred`` as a whole. A panorama with no seen cell is left as is.

    Args:
        pred, target: (B, 3, H, W) linear radiance.
        seen: (B, H, W) bool or {0, 1}: the cells a view shows.
    Returns:
        (B, 3, H, W) the scaled ``pred``.
    """
    from roomlight.core.color import LOG_EPS, luminance_torch

    check_same_shape(pred, target, "seen_matched")
    b, _, h, w = pred.shape
    if tuple(seen.shape) != (b, h, w):
        raise ShapeError(f"seen_matched: expected a (B, H, W) = {(b, h, w)} mask, got {tuple(seen.shape)}")
    omega = pixel_solid_angles(h, w, dtype=pred.dtype, device=pred.device)  # (H, W)
    weight = seen.to(pred.dtype) * omega  # (B, H, W)
    total = weight.flatten(1).sum(1)  # (B,)

    def log_average(rad):
        y = luminance_torch(rad.clamp_min(0.0))  # (B, H, W)
        return (weight * torch.log(y + LOG_EPS)).flatten(1).sum(1) / total.clamp_min(1e-12)

    log_scale = torch.where(total > 0, log_average(target) - log_average(pred), torch.zeros_like(total))
    return pred * torch.exp(log_scale)[:, None, None, None]


def irradiance_loss(pred: torch.Tensor, target: torch.Tensor, eps: float = 1e-6,
                    seen: torch.Tensor | None = None) -> torch.Tensor:
    """Mean |log(E^ + eps) - log(E + eps)| over panoramas, normals and colour channels.

    Args:
        pred, target: (B, 3, H, W) linear radiance in the same units (exposure calibrated).
        eps: offset inside the log, so a black half-sphere stays finite.
        seen: optional (B, H, W) cells a view shows: ``pred`` is first scaled by :func:`seen_matched`,
            so only the unseen part's energy relative to the seen part counts.
    Returns:
        scalar tensor.
    """
    check_same_shape(pred, target, "irradiance_loss")
    if seen is not None:
        pred = seen_matched(pred, target, seen)
    e_hat, e = irradiance_at_centre(pred), irradiance_at_centre(target)
    return (torch.log(e_hat + eps) - torch.log(e + eps)).abs().mean()


@torch.no_grad()
def irradiance_log_ratio(pred: torch.Tensor, target: torch.Tensor, eps: float = 1e-6,
                         seen: torch.Tensor | None = None) -> torch.Tensor:
    """(B,) signed mean over normals of log2(E^ / E) of the luminance (Rec.709): a guess's energy
    bias in stops (negative: too dim). With ``seen`` (B, H, W), after :func:`seen_matched`: the bias
    a photo fit starts with, once its exposure matches the seen part."""
    from roomlight.core.color import REC709_LUMA

    check_same_shape(pred, target, "irradiance_log_ratio")
    if seen is not None:
        pred = seen_matched(pred, target, seen)
    luma = torch.tensor(REC709_LUMA, dtype=pred.dtype, device=pred.device)
    e_hat, e = irradiance_at_centre(pred) @ luma, irradiance_at_centre(target) @ luma  # (B, N)
    return (torch.log2(e_hat + eps) - torch.log2(e + eps)).mean(1)
