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
"""

from __future__ import annotations

import math
from functools import lru_cache

import torch

from roomlight.core.geometry.equirect import pixel_directions, pixel_solid_angles
from roomlight.errors import ShapeError
from roomlight.prior.losses.l1 import check_same_shape

__all__ = ["IRRADIANCE_NORMALS", "irradiance_weights", "irradiance_at_centre", "irradiance_loss",
           "irradiance_log_ratio"]


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


def irradiance_loss(pred: torch.Tensor, target: torch.Tensor, eps: float = 1e-6) -> torch.Tensor:
    """Mean |log(E^ + eps) - log(E + eps)| over panoramas, normals and colour channels.

    Args:
        pred, target: (B, 3, H, W) linear radiance in the same units (exposure calibrated).
        eps: offset inside the log, so a black half-sphere stays finite.
    Returns:
        scalar tensor.
    """
    check_same_shape(pred, target, "irradiance_loss")
    e_hat, e = irradiance_at_centre(pred), irradiance_at_centre(target)
    return (torch.log(e_hat + eps) - torch.log(e + eps)).abs().mean()


@torch.no_grad()
def irradiance_log_ratio(pred: torch.Tensor, target: torch.Tensor, eps: float = 1e-6) -> torch.Tensor:
    """(B,) signed mean over normals of log2(E^ / E) of the luminance (Rec.709): a guess's energy
    bias in stops (negative: too dim)."""
    from roomlight.core.color import REC709_LUMA

    check_same_shape(pred, target, "irradiance_log_ratio")
    luma = torch.tensor(REC709_LUMA, dtype=pred.dtype, device=pred.device)
    e_hat, e = irradiance_at_centre(pred) @ luma, irradiance_at_centre(target) @ luma  # (B, N)
    return (torch.log2(e_hat + eps) - torch.log2(e + eps)).mean(1)
