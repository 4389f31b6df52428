"""The fitting methods by name, and ``fit_scene`` which runs one on a scene description.

=================  ======================================================================
``prior``          z + log-exposure (+ white balance) through the 2.5D area light (the paper's method)
``prior-envmap``   the same prior, its radiance shown at infinity (env-map-prior comparison)
``veni``           z + exposure of VENI, the rotation-equivariant env-map prior (radiance at infinity)
``veni-d``         z + exposure of VENI+D, the same with depth, through the 2.5D area light
``direct-al``      free log radiance + log depth, 2.5D area light, smoothness prior
``direct-sphere``  free log radiance on a sphere proxy enclosing all objects (+20 %)
``direct-envmap``  free log radiance as an env map
=================  ======================================================================
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from roomlight.errors import RoomlightError
from roomlight.inverse.config import FitConfig
from roomlight.inverse.fitter import FitResult, Fitter, mask_window
from roomlight.inverse.lights import DirectLight, LightModel, PriorLight

__all__ = ["METHODS", "PRIOR_METHODS", "VENI_METHODS", "needs_prior", "method_model", "make_light", "enclosing_sphere_radius", "repulsion_object_ids",
           "build_fitter", "fit_scene"]

#: Every method, in the table's order, and whether it fits the latent of a trained prior
#: (and so needs ``--model``) rather than free per-pixel maps.
_NEEDS_PRIOR = {"prior": True, "prior-envmap": True, "veni": True, "veni-d": True, "direct-al": False,
                "direct-sphere": False, "direct-envmap": False}
#: The methods of the VENI models, and whether the method shows the light at infinity.
VENI_METHODS = {"veni": True, "veni-d": False}
METHODS = tuple(_NEEDS_PRIOR)
PRIOR_METHODS = tuple(m for m, prior in _NEEDS_PRIOR.items() if prior)


def needs_prior(method: str) -> bool:
    """Whether ``method`` needs a trained prior (a PanoVAE); False for unknown names (e.g. the oracle)."""
    return _NEEDS_PRIOR.get(method, False)


def enclosing_sphere_radius(scene, margin: float = 0.2) -> float:
    """Smallest origin-centred sphere enclosing every object of every view, enlarged by ``margin``."""
    from roomlight.scene.build import object_geometry

    r = max(float(np.linalg.norm(object_geometry(o)[0], axis=1).max()) for o in scene.objects.values())
    return r * (1.0 + margin)


def method_model(method: str, config: FitConfig, model=None):
    """The model a prior method fits: for ``prior`` / ``prior-envmap`` the given one (a PanoVAE); for
    ``veni`` / ``veni-d`` the given one when it is a VENI model of the method's kind (without / with
    depth), else the one ``config.veni_model`` / ``config.veni_d_model`` names (loaded once per process)."""
    from roomlight.model.families import is_veni

    if method in VENI_METHODS:
        wants_depth = not VENI_METHODS[method]
        if is_veni(model) and model.has_depth == wants_depth:
            return model
        return _load_named(config.veni_d_model if wants_depth else config.veni_model)
    if is_veni(model):
        raise RoomlightError(f"method {method!r} fits the panoramic VAE, and the model given is a VENI model "
                             "(use it with --method veni or veni-d)")
    return model


_LOADED: dict = {}


def _load_named(name: str):
    """A VENI model by name or path, on the renderer's device, loaded once."""
    from roomlight.model.runs import load_run_model, resolve_run_model
    from roomlight.render.variant import torch_device

    device = torch_device()
    key = (str(resolve_run_model(name)), device)
    if key not in _LOADED:
        _LOADED[key] = load_run_model(name, device=device)
    return _LOADED[key]


def make_light(method: str, scene, config: FitConfig, model=None) -> LightModel:
    """The light model of a method (``model``: the prior, needed by the prior methods; see :func:`method_model`)."""
    if method not in METHODS:
        raise RoomlightError(f"unknown method {method!r}; choose one of {', '.join(METHODS)}")
    if needs_prior(method):
        model = method_model(method, config, model)
        if model is None:
            raise RoomlightError(f"method {method!r} needs a trained prior: pass --model RUN_OR_CHECKPOINT")
        envmap = method == "prior-envmap" or VENI_METHODS.get(method, False)
        return PriorLight(model, envmap=envmap, init_exposure=config.init_exposure,
                          z_prior=config.z_prior, fit_depth_scale=config.fit_depth_scale,
                          white_balance=config.white_balance_weight if config.white_balance else None)
    radius = enclosing_sphere_radius(scene, config.sphere_margin)
    kind = {"direct-al": "mesh", "direct-sphere": f"sphere:{radius:.6g}", "direct-envmap": "envmap"}[method]
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
    from roomlight.render.scene import EmitterScene
    from roomlight.scene.build import load_view_target, scene_points, view_objects

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
        from roomlight.inverse.outputs import write_fit_outputs

        write_fit_outputs(out, result, fitter, target=fitter.full_target, mask=fitter.full_mask)
    return result
