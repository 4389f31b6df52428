"""Where the latent of a photo fit starts (``--init``; docs/photo.md, "Start").

- ``view``: the prior's view encoder reads what the photograph shows (its background radiance
  and depth, lifted onto the sphere around the camera; :mod:`roomlight.prior.viewenc`) and predicts the
  room's latent and exposure in one pass. Needs a prior with a view encoder.
- ``samples``: the paper's start: ``init_samples`` draws from N(0, I), keeping the one whose
  decoded room is largest (:func:`roomlight.fitting.photo.placement.initial_latent`).
- ``zero``: the prior's mean room, z = 0.
- ``auto`` (the default): ``view`` when the prior has a view encoder, else ``samples``, else (a
  radiance-only prior such as VENI, whose draws have no depth to rank them by) ``zero``.

Whatever the start, the scene is then placed inside the decoded room and the exposure matched
to the photograph (:mod:`roomlight.fitting.photo.placement`).
"""

from __future__ import annotations

import math

import numpy as np
import torch

from roomlight.errors import RoomlightError

__all__ = ["START_MODES", "resolve_start", "start_latent", "photo_partial_panorama", "view_latent"]

START_MODES = ("auto", "view", "samples", "zero")
#: Pixels of an object's silhouette (at the lifting resolution) left out of the view, since an
#: edge pixel mixes the object and the room.
SILHOUETTE_MARGIN = 1


def resolve_start(mode: str, model) -> str:
    """The start ``mode`` stands for with ``model`` (``auto`` resolved); refuses ``view`` without
    a view encoder."""
    if mode not in START_MODES:
        raise RoomlightError(f"init {mode!r}: expected one of {', '.join(START_MODES)}")
    has_view = getattr(model, "view_encoder", None) is not None
    has_depth = getattr(model, "has_depth", True)
    if mode == "auto":
        return "view" if has_view else "samples" if has_depth else "zero"
    if mode == "view" and not has_view:
        raise RoomlightError("--init view needs a prior with a view encoder (a view_encoder/ folder beside its "
                             "weights; train one with `roomlight train-view-encoder`), or pass --init samples")
    if mode == "samples" and not has_depth:
        # the paper's start ranks its draws by the size of their rooms, which a radiance-only prior lacks
        raise RoomlightError("--init samples ranks random rooms by their depth, which this prior does not "
                             "decode (an env-map prior); pass --init zero")
    return mode


def photo_partial_panorama(case, resolution: tuple[int, int]):
    """What the photograph shows of the room, lifted onto a ``resolution`` panorama around the
    camera (room frame: the camera's pitch and roll applied, no yaw).

    The photograph is brought to about three pixels per panorama cell
    (:func:`~roomlight.core.geometry.lift.lift_resolution`): radiance antialiased, depth and labels by
    nearest neighbour. The objects and a pixel around them are left out; radiance is clipped at 1
    like a recording.
    """
    from roomlight.fitting.photo.camera import camera_rotation
    from roomlight.fitting.photo.geometry import resize_image
    from roomlight.fitting.photo.masks import erode, resize_nearest
    from roomlight.fitting.photo.unproject import unproject
    from roomlight.core.geometry.lift import lift_resolution, lift_view

    k = case.intrinsics
    aspect = case.width / case.height
    h, w = lift_resolution(k.fov_x, aspect, resolution[1])
    if w >= case.width:
        h, w = case.height, case.width
    k_lift = k.scaled(w, h)
    image = np.minimum(resize_image(case.image, h, w), 1.0)
    depth = resize_nearest(case.depth, h, w)
    labels = resize_nearest(case.objects.labels, h, w)
    background = erode(labels == 0, SILHOUETTE_MARGIN)
    points = unproject(depth, k_lift, case.depth_kind)
    return lift_view(torch.from_numpy(points), torch.from_numpy(image), camera_rotation(case.pitch_deg, case.roll_deg),
                     resolution, torch.from_numpy(background))


@torch.no_grad()
def view_latent(model, case, encoder=None, depth: bool = True) -> tuple[torch.Tensor, float, dict]:
    """The view encoder's start: (z (D,), log exposure in the photograph's units, description).

    ``encoder``: the view encoder to read with (default ``model.view_encoder``); ``depth=False``: the
    case's depth is not known (its values only place the pixels' directions) and is withheld from the
    encoder, which should then be one that reads without depth (``ViewEncoder.reads_without_depth``)."""
    from roomlight.prior.model.view_encoder import view_input

    encoder = encoder or model.view_encoder
    partial = photo_partial_panorama(case, model.config.resolution)
    if not bool(partial.seen.any()):
        raise RoomlightError("--init view: the photograph shows no background (every pixel is an object); "
                             "pass --init samples")
    x, k = view_input(partial, model.normalization, depth=depth)
    z, s = encoder(x[None].float())
    log_exposure = math.log(k) + float(s[0])
    return z[0].cpu(), log_exposure, {"seen_fraction": round(partial.seen_fraction, 4),
                                      "view_log_exposure": round(log_exposure, 4)}


def start_latent(mode: str, model, case, config) -> tuple[torch.Tensor, dict]:
    """The starting latent (D,) of a photo fit and a description of it for ``result.json``."""
    from roomlight.fitting.photo.placement import initial_latent

    mode = resolve_start(mode, model)
    if mode == "view":
        z, _, info = view_latent(model, case)
    elif mode == "samples":
        z, medians = initial_latent(model, config.init_samples, config.seed)
        info = {"latent_draws": len(medians), "median_depths": [round(m, 4) for m in medians]}
    else:
        z, info = torch.zeros(model.config.latent_dim), {}
    return z, {"init": mode, **info}
