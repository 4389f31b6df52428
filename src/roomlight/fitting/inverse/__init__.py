"""Illumination recovery by inverse rendering: the prior-guided method and the paper's baselines."""

from roomlight.fitting.inverse.config import FIT_PRESETS, FitConfig, fit_config
from roomlight.fitting.inverse.fitter import FitResult, Fitter
from roomlight.fitting.inverse.lights import DirectLight, LightModel, PriorLight
from roomlight.fitting.inverse.methods import METHODS, build_fitter, enclosing_sphere_radius, fit_scene, make_light
from roomlight.fitting.inverse.objective import censor, image_loss
from roomlight.fitting.inverse.repulsion import clearance, repulsion_penalty
from roomlight.fitting.inverse.smoothness import smoothness

__all__ = ["FIT_PRESETS", "FitConfig", "fit_config", "FitResult", "Fitter", "DirectLight", "LightModel",
           "PriorLight", "METHODS", "build_fitter", "enclosing_sphere_radius", "fit_scene", "make_light", "censor", "image_loss",
           "clearance", "repulsion_penalty", "smoothness"]
