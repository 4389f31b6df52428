"""One training view of the view encoder, with its targets (docs/photo.md, "The view encoder").

From a panorama (radiance calibrated to log-average luminance 1, radial depth in metres):
mirror it or not, cut a random perspective view (:mod:`roomlight.prior.viewenc.crops`), expose and clip
it like a photograph, hide random objects, lift it back onto the sphere
(:mod:`roomlight.core.geometry.lift`) and make the network's input (:func:`view_input`), its depth
withheld with probability ``config.depth_dropout``.

The exposure target follows from the units: the view holds ``e^a · L`` (``a`` from the exposure),
the network input holds that divided by ``k`` (the view's log-average), so the light in the
input's units is ``e^(a - log k) · L`` and ``s* = a - log k``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import torch

from roomlight.core.geometry.lift import lift_view
from roomlight.prior.model.view_encoder import view_input
from roomlight.prior.viewenc.crops import CropSpec, crop_rotation, cut_view, expose, occluder_mask, random_crop_spec

__all__ = ["TrainingView", "training_view"]


@dataclass
class TrainingView:
    """Attributes:
        x: (5, H, W) the network's input.
        mirrored: whether the panorama was mirrored (its targets must be too).
        exposure_target: s* (see the module docstring).
        spec: the view that was cut.
        seen_fraction: share of the panorama's cells the view covers.
        depth_given: whether ``x`` carries the view's depth (False: withheld, the channel is 0).
    """

    x: torch.Tensor
    mirrored: bool
    exposure_target: float
    spec: CropSpec
    seen_fraction: float
    depth_given: bool = True


def training_view(radiance: torch.Tensor, depth: torch.Tensor, rng: np.random.Generator, config,
                  normalization, withhold: bool | None = None) -> TrainingView:
    """A random training view of one panorama (module docstring).

    Args:
        radiance: (3, H, W) calibrated linear radiance; depth: (1, H, W) radial depth, metres.
        rng: the source of every random choice.
        config: a :class:`~roomlight.prior.viewenc.config.ViewTrainConfig`.
        normalization: the prior's :class:`~roomlight.prior.model.normalization.Normalization`.
        withhold: withhold the depth (True), keep it (False), or draw it with ``config.depth_dropout``
            (None; no draw is made when that is 0, so such runs keep their random sequence).
    """
    h, w = radiance.shape[-2:]
    mirrored = bool(config.mirror and rng.random() < 0.5)
    if mirrored:
        radiance, depth = radiance.flip(-1), depth.flip(-1)
    spec = random_crop_spec(rng, w, config.fov_deg, config.pitch_deg, config.roll_deg, config.aspect)
    image, points = cut_view(radiance, depth, spec)
    lo, hi = config.exposure_key
    image, a = expose(image, float(rng.uniform(math.log(lo), math.log(hi))))
    valid = torch.from_numpy(occluder_mask(rng, spec.height, spec.width, config.occluders))
    partial = lift_view(points, image, crop_rotation(spec), (h, w), valid)
    if withhold is None:
        p = float(getattr(config, "depth_dropout", 0.0))
        withhold = bool(p > 0 and rng.random() < p)
    x, k = view_input(partial, normalization, depth=not withhold)
    return TrainingView(x, mirrored, a - math.log(k), spec, partial.seen_fraction, not withhold)
