"""The room's own surfaces bound the light: a visible wall is lit by the rest of the room.

A photograph shows part of the room: its walls, floor and furniture, each at a radiance L_obs. Those
surfaces are not (mostly) light sources: they reflect what the rest of the room sends them, so for a
diffuse surface with albedo rho and irradiance E,

    L_obs = rho * E / pi,   with rho between about 0.03 (black velvet, charcoal) and 0.9 (fresh snow,
                            white paint),

whatever the room. The 2.5D light *is* that room (its surface carries the radiance the photograph sees,
and what the photograph does not see), so the irradiance it delivers to each visible surface point
bounds it from both sides: a fitted light too dim makes the visible walls impossibly white
(rho > 0.9), one too bright impossibly black (rho < 0.03). This is the fact that splits the brightness
between the light and the albedos where the photograph's objects alone cannot, and it holds in any room
(no typical albedo is assumed).

The irradiance is a sum over the emitter's texels (the panorama pooled to a coarse grid), each a flat
patch at its depth with the normal the depth map gives it:

    E(q, n_q) = sum_j L_j max(0, n_q . d_j) D_j^2 dOmega_j |n_j . d_j| / (|n_j . w_j| r_j^2),

where w_j is the texel's direction from the panorama's centre, D_j its depth, dOmega_j its solid angle,
n_j its normal, d_j = (p_j - q) / r_j the direction from q to it. Visibility inside the room is not
traced (the room is star-shaped from its centre, nearly convex from its walls). For an env map (no
depth) the texels are at infinity: E = sum_j L_j max(0, n_q . w_j) dOmega_j. For a closed room of
uniform radiance L, both give E = pi L at every point (tests/test_room_albedo.py checks it against that
and against a ray-traced reference).

Only the photograph's unsaturated pixels count (a saturated pixel is a lamp, a window or a sunlit patch
whose radiance is unknown), and the few points that break the upper bound most are left out (a lamp
shade, a screen, a point whose normal the depth map got wrong): a visible light source is allowed to
be brighter than any reflector.
"""

from __future__ import annotations

import math

import numpy as np
import torch

from roomlight.core.geometry.equirect import pixel_directions, pixel_solid_angles

__all__ = ["RoomSurface", "surface_normals", "lifted", "LIFT", "pool_emitter", "texel_patches", "irradiance",
           "room_albedo_term", "apparent_albedo", "level_bracket", "POOLED_HEIGHT"]

#: The emitter is pooled to this many rows (twice as many columns) before the irradiance sum: the
#: irradiance is a smooth function of the light, and 32 x 64 texels keep the sum at a few ms.
POOLED_HEIGHT = 32


def surface_normals(points: np.ndarray, edge_tolerance: float = 0.05) -> tuple[np.ndarray, np.ndarray]:
    """Unit normals of a grid of camera-frame points, facing the camera.

    Args:
        points: (H, W, 3) the point each pixel sees (camera at the origin), metres.
        edge_tolerance: a neighbour whose distance differs by more than this fraction marks a depth edge.
    Returns:
        ((H, W, 3) float64 normals, (H, W) bool: whether the normal is reliable (all four neighbours on
        the same surface)).
    """
    p = np.asarray(points, dtype=np.float64)
    h, w, _ = p.shape
    du = np.zeros_like(p)
    dv = np.zeros_like(p)
    du[:, 1:-1] = p[:, 2:] - p[:, :-2]
    dv[1:-1] = p[2:] - p[:-2]
    n = np.cross(du, dv)
    norm = np.linalg.norm(n, axis=-1, keepdims=True)
    n = n / np.maximum(norm, 1e-12)
    # Face the camera (the camera is at the origin, so towards -p).
    flip = (n * p).sum(-1) > 0
    n[flip] *= -1
    dist = np.linalg.norm(p, axis=-1)
    ok = np.zeros((h, w), dtype=bool)
    ok[1:-1, 1:-1] = True
    for dy, dx in ((0, 1), (0, -1), (1, 0), (-1, 0)):
        nb = np.roll(dist, (dy, dx), axis=(0, 1))
        ok &= np.abs(nb - dist) <= edge_tolerance * dist
    ok &= norm[..., 0] > 0
    return n, ok


#: A receiving point is lifted off its surface along its normal by this share of its distance from the
#: camera (or the light's centre), so the texels of its own wall do not sit on it.
LIFT = 0.01


def lifted(points, normals):
    """(N, 3) points moved off their surface by :data:`LIFT` of their distance from the origin, along their
    (N, 3) unit normals (NumPy arrays or torch tensors alike)."""
    norm = points.norm(dim=-1, keepdim=True) if isinstance(points, torch.Tensor) else \
        np.linalg.norm(points, axis=-1, keepdims=True)
    return points + LIFT * norm * normals


class RoomSurface:
    """Visible room surfaces in the room frame, as tensors.

    Args:
        points: (N, 3) surface points (metres of the room).
        normals: (N, 3) unit normals facing into the room.
        radiance: (N, 3) the photograph's linear radiance there (saturation-clipped at 1).
    """

    def __init__(self, points, normals, radiance):
        self.points = torch.as_tensor(points, dtype=torch.float32)
        self.normals = torch.as_tensor(normals, dtype=torch.float32)
        self.radiance = torch.as_tensor(radiance, dtype=torch.float32)

    def __len__(self) -> int:
        return len(self.points)

    def where(self, keep: torch.Tensor) -> RoomSurface:
        """The points where the (N,) bool ``keep`` holds."""
        return RoomSurface(self.points[keep], self.normals[keep], self.radiance[keep])


def pool_emitter(radiance: torch.Tensor, depth: torch.Tensor | None, height: int):
    """Radiance (H, W, 3) and depth (H, W) pooled to ``height`` rows (solid-angle weighted)."""
    h = radiance.shape[0]
    if h <= height:
        return radiance, depth
    k = h // height
    omega = pixel_solid_angles(h, 2 * h, dtype=radiance.dtype, device=radiance.device)[..., None]
    pool = torch.nn.functional.avg_pool2d
    wsum = pool(omega.permute(2, 0, 1)[None], k)
    rad = pool((radiance * omega).permute(2, 0, 1)[None], k) / wsum
    rad = rad[0].permute(1, 2, 0)
    if depth is not None:
        # The mean of D^2 (projected area), so the pooled patch keeps the area it stands for.
        d2 = pool((depth[..., None].square() * omega).permute(2, 0, 1)[None], k) / wsum
        depth = d2[0, 0].clamp_min(0).sqrt()
    return rad, depth


def texel_patches(depth: torch.Tensor, min_cosine: float = 0.1):
    """The 2.5D light's texels as flat patches: where each stands, which way it faces, how large it is.

    Args:
        depth: (h, w) radial depth of the (pooled) panorama, w = 2 h, metres.
        min_cosine: floor of |n_j . w_j|, bounding the area of texels seen at grazing angles.
    Returns:
        ((h*w, 3) positions, (h*w, 3) unit normals facing the centre, (h*w,) areas in m^2).
    """
    h, w = depth.shape
    dirs = pixel_directions(h, w, dtype=depth.dtype, device=depth.device)   # (h, w, 3)
    omega = pixel_solid_angles(h, w, dtype=depth.dtype, device=depth.device)
    pos = dirs * depth[..., None]
    # Texel normals from the surface's tangents (columns wrap around, rows are clamped at the poles).
    du = torch.roll(pos, -1, 1) - torch.roll(pos, 1, 1)
    up = torch.cat([pos[:1], pos[:-1]], 0)
    down = torch.cat([pos[1:], pos[-1:]], 0)
    n = torch.cross(du, down - up, dim=-1)
    n = n / n.norm(dim=-1, keepdim=True).clamp_min(1e-12)
    n = torch.where(((n * dirs).sum(-1, keepdim=True) > 0), -n, n)  # inward
    cos_w = (n * dirs).sum(-1).abs().clamp_min(min_cosine)          # |n_j . w_j|
    area = (depth.square() * omega / cos_w).reshape(-1)
    return pos.reshape(-1, 3), n.reshape(-1, 3), area


def irradiance(radiance: torch.Tensor, depth: torch.Tensor | None, points: torch.Tensor, normals: torch.Tensor,
               pooled_height: int = POOLED_HEIGHT, min_cosine: float = 0.1) -> torch.Tensor:
    """Irradiance an emitter delivers to surface points (module docstring), differentiable.

    Args:
        radiance: (H, W, 3) the emitter's linear radiance, W = 2 H.
        depth: (H, W) its radial depth in metres, or None for an env map (texels at infinity).
        points: (N, 3) receiving points in the emitter's frame (metres); unused for an env map.
        normals: (N, 3) their unit normals.
        pooled_height: rows of the texel grid summed over.
        min_cosine: floor of |n_j . w_j|, bounding the area of texels seen at grazing angles.
    Returns:
        (N, 3) irradiance, radiance units times steradians.
    """
    rad, dep = pool_emitter(radiance, depth, pooled_height)
    h, w, _ = rad.shape
    dev, dt = rad.device, rad.dtype
    normals = normals.to(dev, dt)
    L = rad.reshape(-1, 3)
    if dep is None:
        dirs = pixel_directions(h, w, dtype=dt, device=dev)
        omega = pixel_solid_angles(h, w, dtype=dt, device=dev)
        cos_q = (normals @ dirs.reshape(-1, 3).T).clamp_min(0)      # (N, T)
        return cos_q @ (L * omega.reshape(-1, 1))
    pos, n, area = texel_patches(dep, min_cosine)
    q = points.to(dev, dt)
    # Every (point, texel) quantity from dot products (three (N, T) matmuls), never an (N, T, 3)
    # difference: the sum runs at every step of a photo fit, and the broadcast version spent most of
    # its time (and its backward pass most of its memory) building and differentiating that tensor.
    r2 = (q.square().sum(-1, keepdim=True) + pos.square().sum(-1)[None] - 2 * (q @ pos.T)).clamp_min(0)
    # A texel never subtends more than the hemisphere; the floor keeps the one under q finite.
    r2 = torch.maximum(r2, area[None] / (2 * math.pi))
    r = r2.sqrt()
    towards = normals @ pos.T - (normals * q).sum(-1, keepdim=True)   # n_q . (p_j - q)
    facing = q @ n.T - (n * pos).sum(-1)[None]                        # -n_j . (p_j - q)
    cos_q = (towards / r).clamp_min(0)
    solid = (area[None] * (facing / r).clamp_min(0) / r2).clamp_max(2 * math.pi)
    return (cos_q * solid) @ L


def apparent_albedo(radiance: torch.Tensor, depth: torch.Tensor | None, surface: RoomSurface,
                    eps: float = 1e-6) -> torch.Tensor:
    """(N,) pi L_obs / E: the albedo each visible surface point would need under this light (means
    over R, G, B)."""
    e = irradiance(radiance, depth, surface.points, surface.normals).mean(-1)
    return math.pi * surface.radiance.to(e.device).mean(-1) / (e + eps)


def room_albedo_term(radiance: torch.Tensor, depth: torch.Tensor | None, surface: RoomSurface,
                     albedo_range=(0.03, 0.9), trim: float = 0.1, tau: float = 0.99) -> torch.Tensor:
    """Mean squared log-violation of ``albedo_range`` by the visible room's apparent albedos.

    Args:
        radiance, depth: the emitter (exposure applied), as in :func:`irradiance`.
        surface: the visible room (room frame).
        albedo_range: (lo, hi) the albedos real surfaces span.
        trim: the share of points with the largest violations left out (visible light sources).
        tau: a point whose photo pixel reaches tau in any channel is saturated and left out.
    Returns:
        scalar: mean over the kept points of max(0, log a - log hi)^2 + max(0, log lo - log a)^2.
    """
    keep = surface.radiance.amax(-1) < tau
    if not bool(keep.any()):
        return radiance.sum() * 0.0
    sub = surface.where(keep)
    log_a = torch.log(apparent_albedo(radiance, depth, sub).clamp_min(1e-12))
    lo, hi = (math.log(float(a)) for a in albedo_range)
    v = (log_a - hi).clamp_min(0).square() + (lo - log_a).clamp_min(0).square()
    n_keep = len(v) - int(math.floor(trim * len(v)))
    if n_keep < len(v):
        v = torch.sort(v).values[:max(n_keep, 1)]
    return v.mean()


def level_bracket(radiance: torch.Tensor, depth: torch.Tensor | None, surface: RoomSurface,
                  albedo_range=(0.03, 0.9), trim: float = 0.1, tau: float = 0.99) -> dict | None:
    """How far the visible room pins the light's level: the factors k on the light it allows.

    Scaling the light by k divides every visible point's apparent albedo by k. The factors that keep the
    central share of the measured points (all but ``trim`` at each end: lamps, screens, points in a
    shadow the sum does not trace) inside ``albedo_range`` are

        q_hi / hi  <=  k  <=  q_lo / lo,     q_lo, q_hi: the trim and 1 - trim quantiles.

    A point is measured when its photo pixel is neither saturated (a channel at ``tau`` or above: its
    radiance is only a lower bound) nor black (every channel at 0: only an upper bound).

    Args:
        radiance: (H, W, 3) the light's linear radiance, W = 2 H, its exposure applied (the fitted light).
        depth: (H, W) its radial depth in metres, or None for an env map.
        surface: the visible room's points, in the light's frame (:class:`RoomSurface`).
        albedo_range: (lo, hi) the albedos real surfaces span.
        trim: share of the points left out at each end.
        tau: the saturation level of the photograph.
    Returns:
        {"low": k_min, "high": k_max (dimensionless factors on the light's radiance), "points": measured
        points, "trim": trim, "albedo_range": [lo, hi], "albedo_quantiles": [q_lo, q_hi] under this light}
        (low > high: no one factor keeps those points inside the range), or None without a measured point.
    """
    peak = surface.radiance.amax(-1)
    keep = (peak < tau) & (peak > 0)
    if not bool(keep.any()):
        return None
    sub = surface.where(keep)
    with torch.no_grad():
        a = apparent_albedo(radiance.detach(), None if depth is None else depth.detach(), sub)
    q_lo, q_hi = (float(v) for v in torch.quantile(a.double().cpu(), torch.tensor([trim, 1 - trim], dtype=torch.float64)))
    lo, hi = (float(v) for v in albedo_range)
    return {"low": q_hi / hi, "high": q_lo / lo, "points": int(len(a)), "trim": float(trim),
            "albedo_range": [lo, hi], "albedo_quantiles": [q_lo, q_hi]}
