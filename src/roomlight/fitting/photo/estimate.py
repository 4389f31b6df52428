"""A room's light from one ordinary photograph, in seconds: no depth map, no mask (``roomlight estimate``).

What a photograph alone gives: its pixels and, from its EXIF, its field of view. The prior's view
encoder reads what the photograph shows lifted onto the sphere around the camera, with the depth of every
seen pixel, which an ordinary photograph lacks. A geometric guess stands in for it: a floor ``EYE_HEIGHT``
below the camera where a pixel looks down at it, everything else ``GUESS_DISTANCE`` away. (Feeding the
decoded room's own depth back to the encoder does not find the true depth: the decoded room reproduces
the depth it was given to within 1 % in the seen directions, so the guess sets the room's size.)
``without_depth="withheld"`` reads the photograph instead with a prior's depth-optional view encoder
(``view_encoder_depth_optional/``, trained with depth withheld from half its views), which judges the
room's size from what it sees; measured, it makes rooms too small for the objects in a photograph
(docs/results.md), so the guess is the default.
The encoder predicts the room's latent z and its exposure; the camera is the decoded room's centre (the
view encoder decodes the room around the camera, in the photograph's metres), so the light's frame is the
camera's orientation (pitch and roll) and no shift.

``refine_steps`` > 0 continues with a short fit of (z, exposure) to the photograph's own pixels: the
visible room *is* the light seen from its centre, so each pixel must show the light's radiance in its
direction (the censored image loss of the photo fit: a saturated pixel is a lower bound), with the Gaussian
prior on z and each step of z clipped as in the photo fit. No rendering is needed, and no objects.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import torch

from roomlight.errors import InputFileError, RoomlightError

__all__ = ["DEFAULT_FOV", "REFINE_STEPS", "EYE_HEIGHT", "GUESS_DISTANCE", "exif_fov", "first_depth_guess", "Estimate",
           "estimate_light", "estimate_row_settings", "sphere_probes"]

#: Horizontal field of view (degrees) assumed when neither the EXIF nor ``--fov`` gives one: a phone's
#: main camera (26 mm equivalent: 69 degrees on the long side of a 4:3 frame) is the most common
#: photograph; 60 sits between it and a standard lens.
DEFAULT_FOV = 60.0
#: Steps of ``--refine`` (Adam on z and the exposure against the photograph's pixels).
REFINE_STEPS = 40
#: The first depth guess: a floor this far below the camera (metres: a standing photographer's hand) ...
EYE_HEIGHT = 1.5
#: ... and everything else (walls, furniture, the floor beyond) this far away.
GUESS_DISTANCE = 3.5
#: The 35 mm frame's diagonal (mm), which defines a 35 mm-equivalent focal length.
_FULL_FRAME_DIAGONAL = math.hypot(36.0, 24.0)


def exif_fov(path, width: int, height: int) -> tuple[float | None, str]:
    """The horizontal field of view (degrees) of a JPEG/PNG from its EXIF, and where it came from.

    The 35 mm-equivalent focal length f35 (EXIF FocalLengthIn35mmFilm) gives the diagonal field of view
    2 atan(d / 2 f35), d the 35 mm frame's diagonal; the photograph's own aspect splits it into the
    horizontal one. Without f35, the focal length and the focal plane resolution (the sensor's pixel
    pitch) give the same. Returns (None, reason) when the file has neither.
    """
    from PIL import Image

    try:
        with Image.open(path) as im:
            exif = im.getexif()
            sub = exif.get_ifd(0x8769) if exif else {}
    except Exception:  # noqa: BLE001 - any unreadable EXIF is the same as none
        return None, "no readable EXIF"
    tags = {**dict(exif or {}), **dict(sub or {})}
    diag_px = math.hypot(width, height)
    f35 = tags.get(0xA405)
    if f35:
        half_diag = math.atan(_FULL_FRAME_DIAGONAL / (2.0 * float(f35)))
        tan_x = math.tan(half_diag) * width / diag_px
        return math.degrees(2.0 * math.atan(tan_x)), f"EXIF 35 mm-equivalent focal length {float(f35):g} mm"
    f = tags.get(0x920A)
    res_x, unit = tags.get(0xA20E), tags.get(0xA210, 2)
    if f and res_x:
        mm_per_unit = {2: 25.4, 3: 10.0, 4: 1.0}.get(int(unit))
        if mm_per_unit:
            sensor_w = width / float(res_x) * mm_per_unit
            return (math.degrees(2.0 * math.atan(sensor_w / (2.0 * float(f)))),
                    f"EXIF focal length {float(f):g} mm and focal plane resolution")
    return None, "no focal length in its EXIF"


def first_depth_guess(rays_room: np.ndarray, eye_height: float = EYE_HEIGHT,
                      distance: float = GUESS_DISTANCE) -> np.ndarray:
    """(H, W) radial depth of the first guess: a floor ``eye_height`` below the camera where a pixel looks
    down at it nearer than ``distance``, ``distance`` elsewhere.

    Args:
        rays_room: (H, W, 3) unit viewing directions in the room frame (y up).
    """
    down = -rays_room[..., 1]
    with np.errstate(divide="ignore"):
        floor = np.where(down > 1e-6, eye_height / np.maximum(down, 1e-6), np.inf)
    return np.minimum(floor, distance).astype(np.float32)


@dataclass
class Estimate:
    """The light recovered from a photograph.

    Attributes:
        light: the 2.5D light (radiance in the photograph's units, radial depth in metres) in the frame
            camera -> room (the camera at the centre).
        latent: (D,) the prior's latent.
        log_exposure: ln of the factor from the decoded radiance to the photograph's units.
        depth_seen: (H, W) the radial depth the view encoder read for the photograph's pixels (given or
            guessed), or None when it read the photograph without depth.
        info: the depth guess, refinement, timings, for ``result.json``.
    """

    light: object
    latent: torch.Tensor
    log_exposure: float
    depth_seen: np.ndarray | None
    info: dict = field(default_factory=dict)


def _case(image: np.ndarray, camera, depth: np.ndarray, pitch: float, roll: float):
    from roomlight.fitting.photo.case import PhotoCase
    from roomlight.fitting.photo.masks import ObjectLabels

    labels = ObjectLabels(np.zeros(image.shape[:2], np.int32), "binary", [])
    return PhotoCase(image, depth, "radial", camera, labels, pitch_deg=pitch, roll_deg=roll)


def _rays_room(camera, pitch: float, roll: float) -> np.ndarray:
    from roomlight.fitting.photo.camera import camera_rotation

    rays = camera.pixel_rays()
    rays = rays / np.linalg.norm(rays, axis=-1, keepdims=True)
    return rays @ camera_rotation(pitch, roll).T


def estimate_light(image: np.ndarray, camera, model, pitch: float = 0.0, roll: float = 0.0, refine_steps: int = 0,
                   refine_lr: float = 0.05, refine_pixels: int = 4096, tau: float = 0.99, seed: int = 0,
                   depth: np.ndarray | None = None, without_depth: str = "guess") -> Estimate:
    """The light of one photograph (module docstring).

    Args:
        image: (H, W, 3) linear RGB, saturated at 1.
        camera: its :class:`~roomlight.fitting.photo.camera.PhotoCamera`.
        model: a prior with a view encoder (a ``PanoVAE``).
        pitch, roll: the camera's orientation in degrees (level: 0, 0).
        refine_steps: steps of the fit to the photograph's pixels (0: none).
        depth: (H, W) the photograph's radial depth in metres when known.
        without_depth: with no ``depth``, how the photograph is read: ``guess`` (the depth-trained view
            encoder and the geometric guess) or ``withheld`` (the prior's depth-optional view encoder with
            no depth at all; the prior must have one).
    """
    from roomlight.core.light import Light
    from roomlight.fitting.photo.camera import camera_rotation
    from roomlight.fitting.photo.start import view_latent

    if getattr(model, "view_encoder", None) is None:
        raise RoomlightError("estimate needs a prior with a view encoder (a view_encoder/ folder beside its weights; "
                             "train one with `roomlight train-view-encoder`)")
    if not getattr(model, "has_depth", True):
        raise RoomlightError("estimate needs a prior that decodes depth (a 2.5D prior, not an env-map one)")
    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    if without_depth not in ("withheld", "guess"):
        raise RoomlightError(f"without_depth must be guess or withheld, not {without_depth!r}")
    reader = getattr(model, "depth_optional_view_encoder", None)
    if depth is None and without_depth == "withheld" and reader is None:
        raise RoomlightError("this prior has no depth-optional view encoder (view_encoder_depth_optional/ beside "
                             "its weights; train one with `roomlight train-view-encoder --set depth_dropout=0.5`)")
    rays = _rays_room(camera, pitch, roll)
    mode = "given" if depth is not None else without_depth
    # without depth the pixels are lifted at the guess's distances: only their directions matter then
    lifted = np.asarray(depth, np.float32) if mode == "given" else first_depth_guess(rays)
    dev = next(model.parameters()).device
    withheld = mode == "withheld"
    with torch.no_grad():
        z, log_exposure, about = view_latent(model, _case(image, camera, lifted, pitch, roll),
                                             reader if withheld else None, depth=not withheld)
    timings["view_encoder"] = time.perf_counter() - t0
    if mode == "given":
        depth_info = {"given": True, "median_m": round(float(np.median(lifted)), 4)}
    elif mode == "withheld":
        depth_info = {"withheld": True, "encoder": "view_encoder_depth_optional"}
    else:
        depth_info = {"guess": {"eye_height_m": EYE_HEIGHT, "distance_m": GUESS_DISTANCE}}
    info: dict = {"depth": depth_info, "seen_fraction": about["seen_fraction"],
                  "view_log_exposure": round(log_exposure, 4)}
    if refine_steps > 0:
        t1 = time.perf_counter()
        z, log_exposure, info["refine"] = _refine(model, z, log_exposure, image, rays, refine_steps, refine_lr,
                                                  refine_pixels, tau, seed)
        timings["refine"] = time.perf_counter() - t1
    with torch.no_grad():
        rad, dep = model.decode(z[None].to(dev))
    radiance = (rad[0].permute(1, 2, 0) * math.exp(log_exposure)).float().cpu()
    frame = np.eye(4)
    frame[:3, :3] = camera_rotation(pitch, roll)
    light = Light(radiance, dep[0, 0].float().cpu(), "mesh", frame)
    timings["total"] = time.perf_counter() - t0
    info["timings_s"] = {k: round(v, 3) for k, v in timings.items()}
    return Estimate(light, z.detach().cpu(), float(log_exposure), None if withheld else lifted, info)


def estimate_row_settings(name: str) -> dict:
    """:func:`estimate_light`'s keyword arguments for a benchmark row of ``roomlight estimate``
    (:data:`roomlight.fitting.methods.ESTIMATE_ROWS`)."""
    from roomlight.fitting.methods import ESTIMATE_ROWS

    refine, without_depth = ESTIMATE_ROWS[name]
    return {"refine_steps": REFINE_STEPS if refine else 0, "without_depth": without_depth}


def _refine(model, z0: torch.Tensor, s0: float, image: np.ndarray, rays: np.ndarray, steps: int, lr: float,
            pixels: int, tau: float, seed: int, z_prior: float = 1e-4, step_clip: float = 0.1):
    """(z, log exposure, description) after ``steps`` of Adam on the photograph's pixels (module docstring)."""
    from roomlight.core.geometry.equirect import sample_equirect
    from roomlight.fitting.inverse.objective import image_loss

    dev = next(model.parameters()).device
    rng = np.random.default_rng(seed)
    n = image.shape[0] * image.shape[1]
    take = np.sort(rng.choice(n, min(pixels, n), replace=False))
    target = torch.from_numpy(np.minimum(image.reshape(-1, 3)[take], 1.0)).float().to(dev)
    dirs = torch.from_numpy(rays.reshape(-1, 3)[take]).float().to(dev)
    ones = torch.ones(1, len(take), dtype=torch.bool, device=dev)
    z = torch.nn.Parameter(z0.clone().float().to(dev))
    s = torch.nn.Parameter(torch.tensor(float(s0), device=dev))
    opt = torch.optim.Adam([z, s], lr=lr, betas=(0.9, 0.99))
    losses = []

    def loss_of():
        rad, _ = model.decode(z[None])
        seen = sample_equirect(rad * torch.exp(s), dirs)[0].T  # (N, 3)
        return image_loss(seen[None], target[None], ones, tau, 10.0, 0.01, 1e-3)["img"] + z_prior * 0.5 * z.square().sum()

    for _ in range(steps):
        opt.zero_grad()
        loss = loss_of()
        loss.backward()
        before = z.detach().clone()
        opt.step()
        with torch.no_grad():
            step = z - before
            norm = float(step.norm())
            if norm > step_clip:
                z.copy_(before + step * (step_clip / norm))
        losses.append(float(loss.detach()))
    with torch.no_grad():
        final = float(loss_of())
    return z.detach(), float(s.detach()), {"steps": steps, "lr": lr, "pixels": len(take),
                                           "loss_first": round(losses[0], 6), "loss_final": round(final, 6)}


def sphere_probes(light, size: int = 96) -> dict[str, np.ndarray]:
    """Three spheres under the light at infinity, seen from the camera: diffuse (albedo 0.8), matte (a
    glossy lobe, albedo 0.8) and mirror; (size, size, 3) linear radiance each (0 outside the sphere).

    Computed from the panorama directly (no renderer): the mirror looks the reflected direction up; the
    diffuse sphere sums the texels' radiance times the clamped cosine; the matte one a Phong lobe of
    exponent 30 about the reflected direction, normalised to the same albedo.
    """
    from roomlight.core.geometry.equirect import pixel_directions, pixel_solid_angles, sample_equirect

    rad = torch.as_tensor(light.radiance).float()
    h = rad.shape[0]
    k = max(1, h // 32)
    pooled = torch.nn.functional.avg_pool2d(rad.permute(2, 0, 1)[None], k)[0].permute(1, 2, 0)
    ph, pw = pooled.shape[:2]
    texel_dirs = pixel_directions(ph, pw).reshape(-1, 3)
    omega = pixel_solid_angles(ph, pw).reshape(-1, 1)
    L = pooled.reshape(-1, 3)
    rot = torch.tensor(np.array(light.frame, np.float64)[:3, :3], dtype=torch.float32)
    rot = rot / torch.linalg.norm(rot[:, 0])
    v = (torch.arange(size) + 0.5) / size * 2 - 1
    yy, xx = torch.meshgrid(-v, v, indexing="ij")
    inside = xx.square() + yy.square() < 1
    nz = torch.sqrt((1 - xx.square() - yy.square()).clamp_min(0))
    normal_cam = torch.stack([xx, yy, nz], -1)[inside]            # camera frame: looking along -z
    view_cam = torch.tensor([0.0, 0.0, -1.0])
    refl_cam = view_cam - 2 * (normal_cam @ view_cam)[:, None] * normal_cam
    normal, refl = normal_cam @ rot.T, refl_cam @ rot.T             # room frame
    out = {}
    mirror = sample_equirect(rad.permute(2, 0, 1)[None], refl)[0].T
    cos = (normal @ texel_dirs.T).clamp_min(0)
    diffuse = 0.8 / math.pi * cos @ (L * omega)
    lobe = (refl @ texel_dirs.T).clamp_min(0) ** 30 * cos
    lobe = lobe / (lobe * omega.T).sum(1, keepdim=True).clamp_min(1e-12)
    matte = 0.8 * lobe @ (L * omega)
    for name, vals in (("diffuse", diffuse), ("matte", matte), ("mirror", mirror)):
        img = torch.zeros(size, size, 3)
        img[inside] = vals
        out[name] = img.numpy()
    return out


def read_photo_for_estimate(path, fov: float | None = None) -> tuple[np.ndarray, object, dict]:
    """(linear image, camera, where its field of view came from) of a JPEG/PNG/EXR."""
    from roomlight.fitting.photo.camera import PhotoCamera
    from roomlight.fitting.photo.case import read_image

    p = Path(path)
    image, notes = read_image(p)
    h, w = image.shape[:2]
    if fov is not None:
        if not 1.0 <= fov <= 170.0:
            raise InputFileError(p, f"--fov {fov:g} is not a field of view in degrees (1 to 170)")
        about = {"fov_deg": float(fov), "fov_from": "--fov"}
    else:
        found, why = exif_fov(p, w, h) if p.suffix.lower() in (".jpg", ".jpeg", ".png", ".tif", ".tiff") else (
            None, "no EXIF in an EXR")
        if found is not None:
            about = {"fov_deg": round(found, 3), "fov_from": why}
        else:
            about = {"fov_deg": DEFAULT_FOV, "fov_from": f"default ({why})"}
            notes.append(f"{p.name}: {why}; assuming a {DEFAULT_FOV:g} degree horizontal field of view (pass --fov)")
    about["notes"] = notes
    return image, PhotoCamera.from_fov(about["fov_deg"], w, h), about
