"""Settings of illumination fitting (paper §3.4 and supplementary "Fitting details")."""

from __future__ import annotations

from dataclasses import dataclass

from roomlight.core.config import StrictConfig
from roomlight.errors import RoomlightError

__all__ = ["FitConfig", "FIT_PRESETS", "fit_config"]


#: Values of ``FitConfig.repulsion_objects``.
REPULSION_OBJECTS = ("scene", "view")


@dataclass(frozen=True)
class FitConfig(StrictConfig):
    """Every knob of a fit; the defaults are the paper's settings, except the white balance beside the
    paper's scalar exposure (``white_balance=False`` restores it)."""

    iterations: int = 500                 #: optimisation steps
    lr: float = 0.1                       #: Adam learning rate (z, s, and the direct maps alike)
    betas: tuple[float, float] = (0.9, 0.99)  #: Adam betas (0.99: the gradient is a Monte-Carlo estimate)
    grad_clip: float = 0.05               #: global gradient-norm clip
    spp: int = 64                         #: samples per pixel of the fitted view's render
    max_depth: int = 4                    #: longest light path of the prb integrator
    seed: int = 0                         #: base seed; iteration t renders with seed + 2t
    tau: float = 0.99                     #: a target pixel with max channel >= tau counts as saturated
    c_max: float = 10.0                   #: ceiling on unsaturated render pixels
    lambda_log: float = 0.1               #: weight of the log-space image term
    log_eps: float = 1e-3                 #: epsilon of the log-space image term (linear units)
    lambda_rep: float = 0.1               #: weight of the repulsion term
    margin: float = 0.05                  #: repulsion margin m in metres (scene units)
    repulsion_points: int = 512           #: surface points per object for the repulsion term
    #: whose surface points the repulsion keeps inside the emitter: 'scene' (every object of the
    #: scene description, in any view: all the geometry the light will shine on) or 'view'
    #: (only the objects of the fitted view)
    repulsion_objects: str = "scene"
    smooth_radiance: float = 5e-5         #: smoothness weight on log radiance (direct methods)
    smooth_depth: float = 1e-4            #: smoothness weight on log depth (direct-al)
    init_exposure: float = 0.18           #: e^s at the start (prior) / initial radiance (direct)
    direct_resolution: tuple[int, int] = (128, 256)  #: (H, W) of the direct methods' maps
    sphere_margin: float = 0.2            #: sphere proxy = enclosing radius x (1 + this)
    z_prior: float = 0.0                  #: weight of a Gaussian prior 0.5 |z|^2 on the latent
    fit_depth_scale: bool = False         #: also fit a global log scale of the decoded depth
    #: prior methods: fit a white balance c (sum 0) beside the exposure, gain exp(s + c); False is
    #: the paper's scalar exposure
    white_balance: bool = True
    #: weight w of the pull to neutral, w |c|^2; chosen among 0.003, 0.03 and 0.3 on 12 scenes of rooms
    #: no benchmark uses (docs/inverse-rendering.md): the weakest lowered the probe's colour error most
    white_balance_weight: float = 0.003
    #: The models of the ``veni`` and ``veni-d`` methods: a bundled model's name, a model folder or a run
    #: (``--model`` takes their place when it is a VENI model of the method's kind).
    veni_model: str = "veni"
    veni_d_model: str = "veni-d"
    pixel_subset: float = 1.0             #: fraction of object pixels in the loss each step
    eval_every: int = 10                  #: best-iterate check period (fixed-seed re-evaluation)
    eval_spp: int | None = None           #: spp of the best-iterate check (default: spp)
    crop_to_mask: bool = True             #: render only the mask's bounding box while fitting
    view: str = "input"                   #: the scene view to fit
    image: str = "ldr"                    #: target: 'ldr' (8-bit recording) or 'hdr' (linear EXR)

    def __post_init__(self) -> None:
        if not self.white_balance_weight >= 0:
            raise RoomlightError(f"fit setting white_balance_weight must be >= 0, not {self.white_balance_weight!r}")
        if self.repulsion_objects not in REPULSION_OBJECTS:
            raise RoomlightError(f"fit setting repulsion_objects must be one of {', '.join(REPULSION_OBJECTS)}, "
                                 f"not {self.repulsion_objects!r}")


#: ``paper`` = the paper's settings; ``fast`` = a CPU-friendly setting for benchmarks and demos.
FIT_PRESETS: dict[str, FitConfig] = {
    "paper": FitConfig(),
    "fast": FitConfig(iterations=150, spp=16, eval_every=10),
}


def fit_config(preset: str = "paper", **overrides) -> FitConfig:
    """The settings of ``preset`` with some fields changed; an override of None keeps the preset's
    value (command-line options that were not given arrive as None)."""
    if preset not in FIT_PRESETS:
        raise RoomlightError(f"unknown fit preset {preset!r}; choose one of {', '.join(FIT_PRESETS)}")
    return FIT_PRESETS[preset].override(**{k: v for k, v in overrides.items() if v is not None})


