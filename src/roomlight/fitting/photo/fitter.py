"""Fitting a photograph: the light and the objects' materials, jointly (paper §4.3, supp. "Real images").

The loop is the illumination fit's (:class:`~roomlight.fitting.inverse.fitter.Fitter`: render, censored
image loss on the object pixels, repulsion, Adam, fixed-seed best iterate, non-finite guard,
resumable state). A photograph changes four things:

- what is optimised: :class:`PhotoModel` holds the light model *and* the objects' materials,
  whose values reach the renderer with every render (:meth:`PhotoModel.scene_values`);
- the objective adds the frustum constraint (:mod:`roomlight.fitting.photo.frustum`), and the repulsion
  points include free space in the view frustum, so the emitter never hides the scene;
- each step of the latent z is clipped to a norm of ``latent_step_clip`` (instead of clipping the
  gradient's norm);
- the start: the view encoder's room or a large room from N(0, I) (:mod:`roomlight.fitting.photo.start`),
  the scene placed inside it, a matching exposure (:mod:`roomlight.fitting.photo.placement`).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import torch

from roomlight.errors import RoomlightError
from roomlight.fitting.inverse.fitter import FitResult, Fitter, mask_window
from roomlight.fitting.inverse.objective import image_loss
from roomlight.fitting.inverse.lights import DirectLight, LightModel, PriorLight
from roomlight.fitting.methods import PHOTO, methods_for
from roomlight.fitting.methods import method as method_record
from roomlight.fitting.photo.config import PhotoFitConfig
from roomlight.fitting.photo.frustum import FrustumTarget, frustum_terms
from roomlight.fitting.photo.geometry import PhotoGeometry, SceneTransform, build_geometry, level_transform
from roomlight.fitting.photo.materials import ObjectMaterials
from roomlight.fitting.photo.receivers import ShadowReceivers, shadow_receivers
from roomlight.fitting.photo.room_albedo import RoomSurface, level_bracket, lifted, room_albedo_term

__all__ = ["PHOTO_METHODS", "PhotoModel", "PhotoFitter", "PhotoFit", "fit_photo", "STATE_FILE", "containment_floor",
           "containment_points"]

#: The methods a photograph can be fitted with (:mod:`roomlight.fitting.methods`): the priors' latents, each
#: shown as a 2.5D area light or at infinity, and the free env map; the start variants of ``prior``
#: are ``fit-photo --init``.
PHOTO_METHODS = tuple(m for m in methods_for(PHOTO, fitted=True) if method_record(m).init is None)
#: The resumable state of a fit in progress, inside the output folder.
STATE_FILE = ".fit-state.safetensors"


class PhotoModel(LightModel):
    """A light model and the objects' materials, optimised together.

    Args:
        light: the light model.
        materials: the objects' materials.
        albedo_prior: weight of the materials' reflectance prior (:meth:`ObjectMaterials.albedo_prior`);
            0 leaves it out.
        albedo_prior_mean: the typical mean albedo that prior is centred on.
        albedo_prior_average: the mean over R, G, B it holds, ``geometric`` or ``arithmetic``.
        receivers: the shadow receivers' materials (:mod:`roomlight.fitting.photo.receivers`), or None.
        metal_band: weight of the real-metal bound (:meth:`ObjectMaterials.metal_band_term`); 0 leaves it out.
        metal_band_range: the mean albedos (lo, hi) no real metal has.
    """

    def __init__(self, light: LightModel, materials: ObjectMaterials, albedo_prior: float = 0.0,
                 albedo_prior_mean: float = 0.3, albedo_prior_average: str = "arithmetic",
                 receivers: ObjectMaterials | None = None, metal_band: float = 0.0,
                 metal_band_range=(0.06, 0.45)):
        super().__init__()
        self.light_model = light
        self.materials = materials
        self.receivers = receivers
        self.kind = light.kind
        self.albedo_prior = float(albedo_prior)
        self.albedo_prior_mean = float(albedo_prior_mean)
        self.albedo_prior_average = str(albedo_prior_average)
        self.metal_band = float(metal_band)
        self.metal_band_range = tuple(float(b) for b in metal_band_range)

    @property
    def resolution(self):
        return self.light_model.resolution

    @property
    def latent(self) -> torch.nn.Parameter | None:
        """The prior's latent z, or None for a light without one."""
        return getattr(self.light_model, "z", None)

    def emitter(self):
        return self.light_model.emitter()

    def regularizers(self):
        terms = dict(self.light_model.regularizers())
        if self.albedo_prior > 0:
            terms["albedo_prior"] = self.albedo_prior * self.materials.albedo_prior(self.albedo_prior_mean,
                                                                                 self.albedo_prior_average)
        if self.metal_band > 0:
            terms["metal_band"] = self.metal_band * self.materials.metal_band_term(self.metal_band_range)
        return terms

    def describe(self):
        v = self.materials.values().detach()
        out = {**self.light_model.describe(), "mean_albedo": float(v[:, :3].mean()),
               "mean_roughness": float(v[:, 3].mean()), "mean_metallic": float(v[:, 4].mean())}
        if self.receivers is not None:
            out["mean_receiver_albedo"] = float(self.receivers.values().detach()[:, :3].mean())
        return out

    def scene_values(self):
        values = self.materials.scene_values()
        if self.receivers is not None:
            values.update(self.receivers.scene_values())
        return values


class PhotoFitter(Fitter):
    """The fitting loop with the frustum constraint and the latent step clip (module docstring).

    Args (beyond :class:`Fitter`'s):
        frustum: the frustum observations in the room frame, or None.
        room: the visible room's points of the albedo bound, or None.
        receiver_mask: (H, W) bool pixels of the shadow receivers' image term (the whole frame, as
            ``mask``), or None.
    """

    def __init__(self, model: PhotoModel, escene, target, mask, points, config: PhotoFitConfig,
                 sensor_dict=None, window=None, frustum: FrustumTarget | None = None,
                 room: RoomSurface | None = None, receiver_mask: torch.Tensor | None = None):
        self.frustum = frustum if frustum is not None and len(frustum) else None
        self.room = room if room is not None and len(room) and config.room_albedo > 0 else None
        super().__init__(model, escene, target, mask, points, config, sensor_dict=sensor_dict, window=window)
        self.receiver_mask = None
        if receiver_mask is not None and bool(receiver_mask.any()) and config.lambda_receivers > 0:
            self.receiver_mask = self.in_window(receiver_mask.bool())

    def fits_without_pixels(self) -> bool:
        # A photo without objects: the light is fitted to the visible room alone (frustum, room bound).
        return self.frustum is not None or self.room is not None

    def terms(self, image, radiance, depth, mask):
        t = super().terms(image, radiance, depth, mask)
        c = self.config
        if self.receiver_mask is not None and image is not None:
            # The receivers' pixels under the same censored loss as the objects' (their shadows say how
            # much light came through the directions the objects hide; receivers.py).
            t["receivers"] = image_loss(image, self.target, self.receiver_mask, c.tau, c.c_max, c.lambda_log,
                                        c.log_eps)["img"]
            t["total"] = t["total"] + c.lambda_receivers * t["receivers"]
        if self.frustum is not None and (c.lambda_frustum > 0 or (depth is not None and c.lambda_frustum_depth > 0)):
            f = frustum_terms(radiance, depth, self.frustum, c.tau, c.c_max, c.lambda_log, c.log_eps)
            t.update(f)
            t["total"] = t["total"] + c.lambda_frustum * f["frustum"]
            if "frustum_depth" in f:
                t["total"] = t["total"] + c.lambda_frustum_depth * f["frustum_depth"]
        if self.room is not None:
            rad_r, depth_r = radiance, depth
            if c.room_albedo_moves == "exposure":
                # The bound says how bright the light is, not where its light comes from: its gradient
                # reaches the light's level only (the exposure s; for a free map, its mean).
                s = getattr(self.light.light_model, "s", None)
                level = s if isinstance(s, torch.Tensor) else torch.log(radiance.mean())
                rad_r = radiance.detach() * torch.exp(level - level.detach())
                depth_r = None if depth is None else depth.detach()
            t["room_albedo"] = room_albedo_term(rad_r, depth_r, self.room, tuple(c.room_albedo_range),
                                                c.room_albedo_trim, c.tau)
            t["total"] = t["total"] + c.room_albedo * t["room_albedo"]
        return t

    def update(self) -> float:
        c = self.config
        grads = [p.grad for p in self.params if p.grad is not None]
        gnorm = float(torch.linalg.vector_norm(torch.stack([g.norm() for g in grads]))) if grads else 0.0
        if c.grad_clip > 0:
            torch.nn.utils.clip_grad_norm_(self.params, c.grad_clip)
        z = self.light.latent
        before = z.detach().clone() if z is not None and z.requires_grad else None
        self.optimizer.step()
        if before is not None and c.latent_step_clip > 0:
            with torch.no_grad():
                step = z - before
                n = float(step.norm())
                if n > c.latent_step_clip:
                    z.copy_(before + step * (c.latent_step_clip / n))
        return gnorm


@dataclass
class PhotoFit:
    """A fitted photograph.

    Attributes:
        method: the method's name.
        result: the light's :class:`FitResult` (radiance, depth, history, best iterate).
        model: the fitted :class:`PhotoModel` (best iterate loaded).
        fitter: the fitter (its ``escene`` holds the objects, the sensor and the fitted light).
        geometry: the photograph prepared for fitting (camera frame).
        transform: camera frame -> room frame of the light.
        objective: every term of the objective at the best iterate (fixed seed).
        timings: seconds per phase.
        initial: how the fit started (latent draws, exposure, placement).
        containment: for a 2.5D light, how many free-space and object points it had to enclose,
            whether the depth floor held them, and the share of each left outside (0 with the floor).
        receivers: the shadow receivers' geometry (:mod:`roomlight.fitting.photo.receivers`), or None.
        level_bracket: the factors on the fitted light the visible room allows
            (:func:`~roomlight.fitting.photo.room_albedo.level_bracket`), or None (no usable room points).
    """

    method: str
    result: FitResult
    model: PhotoModel
    fitter: PhotoFitter
    geometry: PhotoGeometry
    transform: SceneTransform
    objective: dict
    timings: dict = field(default_factory=dict)
    initial: dict = field(default_factory=dict)
    containment: dict = field(default_factory=dict)
    receivers: ShadowReceivers | None = None
    level_bracket: dict | None = None

    @property
    def materials(self) -> ObjectMaterials:
        return self.model.materials


def _initial_light(method: str, geometry: PhotoGeometry, config: PhotoFitConfig, model, case) -> tuple:
    """(light model, scene transform, description of the start) of ``method``."""
    from roomlight.fitting.photo.placement import matching_log_exposure, matching_white_balance, place_scene
    from roomlight.fitting.photo.start import start_latent

    base = level_transform(case)
    obs_room_dirs = base.directions(geometry.frustum.rays)
    if method not in PHOTO_METHODS:
        raise RoomlightError(f"unknown photo method {method!r}; choose one of {', '.join(PHOTO_METHODS)}")
    record = method_record(method)
    if record.source == "latent":
        from roomlight.fitting.inverse.methods import method_model

        model = method_model(method, config, model)
        if model is None:
            raise RoomlightError(f"method {method!r} needs a trained prior (--model)")
        as_mesh = record.light == "mesh"
        z0, start = start_latent(config.init, model, case, config)
        light = PriorLight(model, envmap=not as_mesh, init_exposure=1.0, z_prior=config.z_prior,
                           white_balance=config.white_balance_weight if config.white_balance else None,
                           z_anchor=config.z_anchor)
        with torch.no_grad():
            light.z.copy_(z0.to(light.z.device))
            rad, depth = model.decode(z0[None].to(next(model.parameters()).device))
            rad = rad[0].permute(1, 2, 0).cpu()
            depth = None if depth is None else depth[0, 0].cpu()
        light.anchor_here()
        if as_mesh and start["init"] == "view":
            # The view encoder decodes the room around the camera, in the photograph's metres: the
            # camera is its centre. (Placing the scene anew would let it shrink the photograph into
            # a patch of wall that fits its depths better: seen at 0.2x scale, 2 m off centre.)
            transform, dirs = base, obs_room_dirs
        elif as_mesh:
            repelled = np.concatenate([geometry.object_points, geometry.free_points])
            transform = place_scene(depth, base.rotation, geometry.frustum.points, repelled, config.margin,
                                    config.lambda_rep, config.placement_steps)
            dirs = transform.points(geometry.frustum.points)
        else:  # at infinity nothing depends on where the scene is
            transform, dirs = base, obs_room_dirs
        s0 = matching_log_exposure(rad, dirs, geometry.frustum.radiance, config.tau)
        s0 += config.start_exposure_ev * math.log(2.0)
        with torch.no_grad():
            light.s.fill_(s0)
        info = {**start, "z_norm": float(z0.norm()), "exposure": math.exp(s0)}
        if light.c is not None:  # the colour of the background the camera sees, as the level is its brightness
            c0 = matching_white_balance(rad, dirs, geometry.frustum.radiance, config.tau)
            with torch.no_grad():
                light.c.copy_(torch.as_tensor(c0, dtype=light.c.dtype))
            info["white_balance"] = [round(float(v), 6) for v in np.exp(c0)]
        return light, transform, info
    # free maps (the photo's only one is an env map: without depth nothing places them in the room)
    from roomlight.core.color import log_average_np

    obs = geometry.frustum.radiance
    keep = obs.max(-1) < config.tau
    level = log_average_np(obs[keep]) if keep.any() else config.init_exposure
    level *= 2.0 ** config.start_exposure_ev
    light = DirectLight(record.light, config.direct_resolution, init_radiance=float(level),
                        smooth_radiance=config.smooth_radiance, smooth_depth=config.smooth_depth)
    return light, base, {"initial_radiance": float(level)}


def _state_tag(method: str, case, light: LightModel, receivers: ObjectMaterials | None = None) -> dict:
    """What a saved fit state must have been made for: the method, its light, the photograph (a digest of
    the image, depth and labels) and the shadow receivers, so a state is never resumed for another fit."""
    import hashlib

    h = hashlib.sha256()
    for a in (case.image, case.depth, case.objects.labels):
        h.update(np.ascontiguousarray(a).tobytes())
    return {"method": method, "light": type(light).__name__, "kind": str(light.kind), "photo": h.hexdigest()[:16],
            "depth_kind": case.depth_kind, "intrinsics": case.intrinsics.intrinsics_dict(),
            "pitch_roll": [case.pitch_deg, case.roll_deg],
            **({"receivers": list(receivers.labels)} if receivers is not None else {})}


def fit_photo(case, method: str = "prior", config: PhotoFitConfig | None = None, model=None, out_dir=None,
              progress: bool = True, light: LightModel | None = None, transform: SceneTransform | None = None,
              materials: ObjectMaterials | None = None, resume: bool = True) -> PhotoFit:
    """Fit the light and the objects' materials of a :class:`~roomlight.fitting.photo.case.PhotoCase`.

    Args:
        method: ``prior`` (2.5D light from the prior), ``prior-envmap``, ``veni`` (env map),
            ``veni-d`` (2.5D light from VENI+D) or ``direct-envmap``.
        config: the settings (default: the paper's).
        model: the prior (a PanoVAE) for the prior methods.
        out_dir: where ``history.jsonl`` and the resumable state go (other outputs:
            :func:`roomlight.fitting.photo.outputs.write_photo_outputs`).
        light, transform: replace the method's light model and the placement (e.g. a known light
            with frozen parameters, to fit the materials alone); ``method`` then only names the fit.
        materials: replaces the default materials (all values 0.5), e.g. with some held fixed.
        resume: continue from the state saved in ``out_dir`` by an interrupted fit.
    """
    from roomlight.core.render.scene import EmitterScene
    from roomlight.fitting.photo.scene import object_shapes, photo_sensor

    config = (config or PhotoFitConfig()).validate()
    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    geometry = build_geometry(case, config)
    timings["geometry"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    info: dict = {}
    if light is None:
        light, placed, info = _initial_light(method, geometry, config, model, case)
        transform = transform or placed
    elif transform is None:
        transform = level_transform(case)
    timings["initialisation"] = time.perf_counter() - t0

    contained = containment_points(geometry, transform) if light.kind == "mesh" else None
    if contained is not None and config.contain and hasattr(light, "depth_floor"):
        light.depth_floor = containment_floor(contained, light.resolution, config)

    if materials is None:
        materials = ObjectMaterials(geometry.labels_present, albedo_range=tuple(config.albedo_range))
    # The reflectance prior and the room's albedo bound settle how the brightness splits between a free
    # light and the albedos; under a light held fixed there is nothing to split: the prior would only bias
    # the albedos, the bound would be a constant.
    light_is_free = any(p.requires_grad for p in light.parameters())
    # Shadow receivers say how bright the light is that the objects hide; under a light held fixed they
    # would only fit their own albedos.
    receivers = shadow = None
    shapes = object_shapes(geometry.objects, transform)
    if config.shadow_receivers and light_is_free:
        shadow = shadow_receivers(geometry, case, config)
    if shadow is not None:
        receivers = ObjectMaterials([m.label for m in shadow.meshes], free=("albedo",), kind="receiver")
        for label in receivers.labels:
            receivers.set_values(label, roughness=1.0, metallic=0.0)
        shapes.update(object_shapes(shadow.meshes, transform,
                                    {lab: receivers.bsdf(lab) for lab in receivers.labels}, kind="receiver"))
    photo_model = PhotoModel(light, materials, config.albedo_prior if light_is_free else 0.0,
                             config.albedo_prior_mean, config.albedo_prior_average, receivers=receivers,
                             metal_band=config.metal_band if light_is_free else 0.0,
                             metal_band_range=tuple(config.metal_band_range))
    sensor = photo_sensor(geometry.intrinsics, transform)
    escene = EmitterScene(light.kind, light.resolution, objects=shapes,
                          sensor=sensor, integrator={"type": "prb", "max_depth": int(config.max_depth)})
    points = torch.from_numpy(transform.points(np.concatenate([geometry.object_points, geometry.free_points]))).float()
    frustum = FrustumTarget(transform.points(geometry.frustum.points), transform.directions(geometry.frustum.rays),
                            geometry.frustum.radiance)
    target = torch.from_numpy(geometry.target)
    mask = torch.from_numpy(geometry.loss_mask)
    receiver_mask = torch.from_numpy(shadow.mask) if shadow is not None else None
    seen = mask if receiver_mask is None else mask | receiver_mask
    window = mask_window(seen) if config.crop_to_mask else None
    fitter = PhotoFitter(photo_model, escene, target, mask, points, config, sensor_dict=sensor, window=window,
                         frustum=frustum, room=(_room_surface(geometry, transform, config.room_albedo_points, config.seed)
                               if light_is_free and config.room_albedo > 0 else None),
                         receiver_mask=receiver_mask)

    out = Path(out_dir) if out_dir is not None else None
    state = None
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        state = out / STATE_FILE
        if not resume and state.exists():
            state.unlink()
    t0 = time.perf_counter()
    result = fitter.run(progress=progress, history_path=out / "history.jsonl" if out else None, state_path=state,
                        checkpoint_every=config.checkpoint_every,
                        state_tag=_state_tag(method, case, light, receivers))
    result.method = method
    timings["fit"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    objective = fitter.evaluate_terms()
    timings["final_evaluation"] = time.perf_counter() - t0
    if contained is not None and result.depth is not None:
        from roomlight.fitting.inverse.floor import outside_share

        containment = {
            "floor": bool(config.contain and getattr(light, "depth_floor", None) is not None),
            "surface_floor": config.surface_floor,
            "free_space_points": len(contained[0]), "object_points": len(contained[1]),
            "free_space_outside_share": outside_share(result.depth, torch.from_numpy(contained[0])),
            "objects_outside_share": outside_share(result.depth, torch.from_numpy(contained[1]))}
    else:
        containment = {}
    room = _room_surface(geometry, transform)
    bracket = None if room is None else level_bracket(result.radiance, result.depth, room,
                                                      tuple(config.room_albedo_range), config.level_bracket_trim,
                                                      config.tau)
    return PhotoFit(method, result, photo_model, fitter, geometry, transform, objective, timings, info, containment,
                    shadow, bracket)


def _room_surface(geometry: PhotoGeometry, transform: SceneTransform, limit: int | None = None,
                  seed: int = 0) -> RoomSurface | None:
    """The visible room's points (room frame): the frustum samples (already at most ``frustum_pixels``) whose
    depth map gives a reliable normal, all of them or a fixed random subset of ``limit`` (drawn with
    ``seed``)."""
    f = geometry.frustum
    if f.normals is None:
        return None
    idx = np.flatnonzero(f.normal_ok)
    if limit is not None and len(idx) > limit:
        idx = np.sort(np.random.default_rng(seed).choice(idx, limit, replace=False))
    if not len(idx):
        return None
    pts = lifted(f.points[idx], f.normals[idx])   # off the surface, so its own wall's texels do not sit on it
    return RoomSurface(transform.points(pts), transform.directions(f.normals[idx]), f.radiance[idx])


def containment_floor(contained, resolution: tuple[int, int], config: PhotoFitConfig) -> torch.Tensor:
    """(H, W) float32 floor under a 2.5D light's depth (:mod:`roomlight.fitting.inverse.floor`) for the points
    of :func:`containment_points`.

    The objects' vertices always get the enclosing floor (an object poking out of the light renders black);
    the point every pixel sees (the visible room, and the objects' fronts, which their vertices enclose
    anyway) gets it too by default (``surface_floor`` = ``neighbours``), or only its own cell's (``cell``),
    so that the light's seen part can lie on the surfaces themselves instead of up to the farthest
    neighbour's distance behind them.
    """
    from roomlight.fitting.inverse.floor import depth_floor

    free, objects = contained
    floor_objects = depth_floor(torch.from_numpy(objects), resolution, float(config.margin))
    floor_surface = depth_floor(torch.from_numpy(free), resolution, neighbours=config.surface_floor == "neighbours")
    return torch.maximum(floor_objects, floor_surface)


def containment_points(geometry: PhotoGeometry, transform: SceneTransform) -> tuple[np.ndarray, np.ndarray]:
    """(free-space points (N, 3), object points (K, 3)) in the room frame that a 2.5D light must enclose:
    every pixel's free space up to the surface it sees, and every object vertex (with ``margin`` to spare,
    :func:`containment_floor`)."""
    free, objects = geometry.contained_points()
    return transform.points(free), transform.points(objects)
