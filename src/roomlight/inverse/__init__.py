"""Illumination recovery by inverse rendering: the prior-guided method and the paper's baselines."""

from roomlight.inverse.config import FIT_PRESETS, FitConfig, fit_config
from roomlight.inverse.fitter import FitResult, Fitter
from roomlight.inverse.lights import DirectLight, LightModel, PriorLight
from roomlight.inverse.methods import METHODS, build_fitter, enclosing_sphere_radius, fit_scene, make_light
from roomlight.inverse.objective import censor, image_loss
from roomlight.inverse.repulsion import clearance, repulsion_penalty
from roomlight.inverse.smoothness import smoothness

__all__ = ["FIT_PRESETS", "FitConfig", "fit_config", "FitResult", "Fitter", "DirectLight", "LightModel",
           "PriorLight", "METHODS", "build_fitter", "enclosing_sphere_radius", "fit_scene", "make_light", "censor", "image_loss",
           "clearance", "repulsion_penalty", "smoothness"]
