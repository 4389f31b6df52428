"""The fitting methods of a scene description (``roomlight fit``, ``bench run``) and ``fit_scene``,
which runs one: what each method is lives in :mod:`roomlight.fitting.methods`; this module turns a name into
the light model it optimises (:func:`make_light`) and the model it fits (:func:`method_model`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from roomlight.errors import RoomlightError
from roomlight.fitting.methods import FIT, methods_for, needs_prior
from roomlight.fitting.methods import method as _method
from roomlight.fitting.inverse.config import FitConfig
from roomlight.fitting.inverse.fitter import FitResult, Fitter, mask_window
from roomlight.fitting.inverse.lights import DirectLight, LightModel, PriorLight

__all__ = ["METHODS", "PRIOR_METHODS", "needs_prior", "method_model", "make_light", "enclosing_sphere_radius",
           "repulsion_object_ids", "build_fitter", "fit_scene"]

#: The methods fitted to a scene's view, in table order.
METHODS = methods_for(FIT, fitted=True)
#: Those that fit the latent of a trained model (and so need one).
PRIOR_METHODS = tuple(m for m in METHODS if needs_prior(m))


def enclosing_sphere_radius(scene, margin: float = 0.2) -> float:
    """Smallest origin-centred sphere enclosing every object of every view, enlarged by ``margin``."""
    from roomlight.fitting.scene.build import object_geometry

    r = max(float(np.linalg.norm(object_geometry(o)[0], axis=1).max()) for o in scene.objects.values())
    return r * (1.0 + margin)


def method_model(name: str, config: FitConfig, model=None):
    """The model a prior method fits: for ``prior`` / ``prior-envmap`` the given one (a PanoVAE); for
    ``veni`` / ``veni-d`` the given one when it is a VENI model of the method's kind (without / with
    depth), else the one ``config.veni_model`` / ``config.veni_d_model`` names (loaded once per process)."""
    from roomlight.prior.model.families import is_veni

    family = _method(name).model
    if family in ("veni", "veni-d"):
        wants_depth = family == "veni-d"
        if is_veni(model) and model.has_depth == wants_depth:
            return model
        return _load_named(config.veni_d_model if wants_depth else config.veni_model)
    if is_veni(model):
        raise RoomlightError(f"method {name!r} fits the panoramic VAE, and the model given is a VENI model "
                             "(use it with --method veni or veni-d)")
    return model


_LOADED: dict = {}


def _load_named(name: str):
    """A VENI model by name or path, on the renderer's device, loaded once."""
    from roomlight.prior.model.runs import load_run_model, resolve_run_model
    from roomlight.core.render.variant import torch_device

    device = torch_device()
    key = (str(resolve_run_model(name)), device)
    if key not in _LOADED:
        _LOADED[key] = load_run_model(name, device=device)
    return _LOADED[key]


def make_light(name: str, scene, config: FitConfig, model=None) -> LightModel:
    """The light model of a method (``model``: the prior, needed by the prior methods; see :func:`method_model`)."""
    if name not in METHODS:
        raise RoomlightError(f"unknown method {name!r}; choose one of {', '.join(METHODS)}")
    m = _method(name)
    if m.needs_prior:
        model = method_model(name, config, model)
        if model is None:
            raise RoomlightError(f"method {name!r} needs a trained prior: pass --model RUN_OR_CHECKPOINT")
        return PriorLight(model, envmap=m.light == "envmap", init_exposure=config.init_exposure,
                          z_prior=config.z_prior, fit_depth_scale=config.fit_depth_scale,
                          white_balance=config.white_balance_weight if config.white_balance else None)
    radius = enclosing_sphere_radius(scene, config.sphere_margin)
    kind = f"sphere:{radius:.6g}" if m.light == "sphere" else m.light
    return DirectLight(kind, config.direct_resolution, init_radiance=config.init_exposure, init_depth=radius,
                       smooth_radiance=config.smooth_radiance, smooth_depth=config.smooth_depth)


def repulsion_object_ids(scene, view, config: FitConfig) -> list[str]:
    """The objects whose surface points the repulsion term keeps inside the emitter.

    ``'scene'`` (default): every object of the scene, also those the fitted view does not show.
    The light is recovered to shine on all of them, and an object left outside the fitted mesh
    is hidden behind it from the capture point and sees only its back faces, which emit nothing
    (a benchmark's evaluation probe outside the fitted room vanishes behind the emitter). The
    sphere proxy and ``direct-al``'s starting sphere enclose every object for the same reason.
    ``'view'``: only the fitted view's objects.
    """
    return list(scene.objects) if config.repulsion_objects == "scene" else list(view.objects)


def build_fitter(scene, light: LightModel, config: FitConfig) -> Fitter:
    """A :class:`Fitter` of ``light`` against the scene's view ``config.view``."""
    from roomlight.core.render.scene import EmitterScene
    from roomlight.fitting.scene.build import load_view_target, scene_points, view_objects

    view = scene.view(config.view)
    target, mask = load_view_target(view, config.image)
    sensor = view.camera.sensor()
    escene = EmitterScene(light.kind, light.resolution, objects=view_objects(scene, view), sensor=sensor,
                          integrator={"type": "prb", "max_depth": int(config.max_depth)})
    points = None
    if light.has_depth:
        points = scene_points(scene, repulsion_object_ids(scene, view, config), config.repulsion_points,
                              seed=config.seed)
    window = mask_window(mask) if config.crop_to_mask else None
    return Fitter(light, escene, target, mask, points, config, sensor_dict=sensor, window=window)


def fit_scene(scene, method: str, config: FitConfig | None = None, out_dir=None, model=None,
              progress: bool = True, light: LightModel | None = None) -> FitResult:
    """Fit ``method`` to the scene's view ``config.view``; write outputs to ``out_dir`` if given.

    ``light`` replaces the method's default light model (e.g. a DirectLight started from a
    given panorama); ``method`` then only names the result.
    """
    config = config or FitConfig()
    light = light if light is not None else make_light(method, scene, config, model)
    fitter = build_fitter(scene, light, config)
    out = Path(out_dir) if out_dir is not None else None
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
    result = fitter.run(progress=progress, history_path=out / "history.jsonl" if out else None)
    result.method = method
    if out is not None:
        from roomlight.fitting.inverse.outputs import write_fit_outputs

        write_fit_outputs(out, result, fitter, target=fitter.full_target, mask=fitter.full_mask)
    return result
