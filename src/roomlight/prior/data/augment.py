"""Training augmentations that preserve the equirectangular parametrisation (supp. "Training details").

- **azimuth roll**: a rotation about the vertical axis by a whole number of pixel columns; exact
  (``torch.roll``), no resampling;
- **horizontal mirror**: u -> 1 - u, i.e. the reflection x -> -x of the scene; exact;
- **tilt**: a true rotation of the sphere by up to ``max_deg`` about a random horizontal axis,
  resampled bilinearly with seam- and pole-continuous interpolation
  (:func:`roomlight.core.geometry.rotate_panorama`). Depth is radial distance from the capture point,
  which a rotation about that point does not change, so depth maps rotate with the same call
  and keep their values.

All functions work on batches and draw every random number from an explicit
``torch.Generator`` so that training stays reproducible and resumable.
"""

from __future__ import annotations

import math

import torch

from roomlight.core.geometry.rotation import rotate_panorama, rotation_matrix

__all__ = ["roll_azimuth", "mirror", "tilt_rotations", "tilt", "augment_batch"]


def roll_azimuth(x: torch.Tensor, shifts: torch.Tensor | int) -> torch.Tensor:
    """Roll each panorama of (B, C, H, W) ``x`` by ``shifts`` columns (int or (B,) int64).

    A shift of s columns rotates the scene about the vertical axis by 2 pi s / W (content moves
    towards larger u).
    """
    if isinstance(shifts, int):
        return torch.roll(x, shifts, dims=-1)
    b, c, h, w = x.shape
    cols = torch.arange(w, device=x.device)
    idx = torch.remainder(cols[None, :] - shifts.to(x.device)[:, None], w)  # (B, W) source column
    return x.gather(-1, idx[:, None, None, :].expand(b, c, h, w))


def mirror(x: torch.Tensor, flags: torch.Tensor | bool = True) -> torch.Tensor:
    """Mirror (B, C, H, W) panoramas left-right where ``flags`` ((B,) bool, or one bool) is set.

    Column j goes to W - 1 - j, so u -> 1 - u at pixel centres exactly: the scene is reflected
    in the plane x = 0 (u = 0 looks along -z and stays there).
    """
    if isinstance(flags, bool):
        return x.flip(-1) if flags else x
    return torch.where(flags.to(x.device)[:, None, None, None], x.flip(-1), x)


def tilt_rotations(angles: torch.Tensor, axis_azimuths: torch.Tensor) -> torch.Tensor:
    """(B, 3, 3) rotations by ``angles`` (radians) about horizontal axes.

    The axis of sample b is (cos a, 0, sin a) with a = ``axis_azimuths[b]``: horizontal (y is
    up), so the rotation tilts the horizon by the angle without turning the room about y.
    """
    mats = [rotation_matrix((math.cos(a), 0.0, math.sin(a)), float(t))
            for t, a in zip(angles.tolist(), axis_azimuths.tolist())]
    return torch.stack(mats)


def tilt(x: torch.Tensor, rotations: torch.Tensor) -> torch.Tensor:
    """Rotate (B, C, H, W) panoramas (radiance and/or depth channels) by (B, 3, 3) rotations.

    A light seen in direction d before the tilt is seen in direction R d after it.
    """
    return rotate_panorama(x, rotations)


def augment_batch(radiance: torch.Tensor, depth: torch.Tensor, generator: torch.Generator,
                  roll: bool = True, flip: bool = True, tilt_deg: float = 7.0
                  ) -> tuple[torch.Tensor, torch.Tensor]:
    """Randomly tilt, mirror and roll a batch (same transform for its radiance and depth).

    Args:
        radiance: (B, 3, H, W) linear radiance.
        depth: (B, 1, H, W) radial depth.
        generator: CPU generator; all random numbers come from it, always in the same order and
            number (whatever the flags), so the stream does not depend on the settings.
        roll: uniform azimuth roll by 0..W-1 columns.
        flip: mirror with probability 1/2.
        tilt_deg: maximum tilt; angles uniform in [-tilt_deg, tilt_deg] degrees, about an axis of
            uniform horizontal direction. 0 disables the tilt (and its resampling).
    Returns:
        augmented (radiance, depth), same shapes.
    """
    b, _, _, w = radiance.shape
    shifts = torch.randint(0, w, (b,), generator=generator)
    flags = torch.rand(b, generator=generator) < 0.5
    angles = (torch.rand(b, generator=generator, dtype=torch.float64) * 2.0 - 1.0) * math.radians(tilt_deg)
    axes = torch.rand(b, generator=generator, dtype=torch.float64) * (2.0 * math.pi)
    x = torch.cat([radiance, depth], dim=1)
    if tilt_deg > 0:
        # Interpolate linear radiance (not its log), so that resampling conserves energy locally.
        x = tilt(x, tilt_rotations(angles, axes))
    if flip:
        x = mirror(x, flags)
    if roll:
        x = roll_azimuth(x, shifts)
    return x[:, :3].clamp_min(0.0), x[:, 3:]
