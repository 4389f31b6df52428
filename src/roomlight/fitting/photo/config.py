"""Settings of fitting a photograph (paper §4.3 and supplementary "Real images").

:class:`PhotoFitConfig` extends the illumination-fitting settings (:class:`FitConfig`, whose
fields keep their meaning: learning rate, Adam's betas, censoring, log term, repulsion margin,
best-iterate checks, ...) with what a photograph adds: the resolutions of the depth mesh and of
the rendered image, the latent step clip, the frustum constraint, the initialisation and the
probes. The defaults are the paper's real-image settings where it gives them:

- 1000 steps at learning rate 0.1, latent step norms clipped to 0.1, lambda_log = 0.01;
- a Gaussian prior on z; lambda_rep = 1 with points sampled in the view frustum;
- depth meshed at 1024 px (longest side), rendered at 640 px with 128 samples per pixel;
- initialisation from a N(0, I) sample with a large room.

The paper does not give the weight of the Gaussian prior or of the frustum terms, nor the
number of initial samples; the values here are roomlight's (documented in docs/photo.md). The
``view`` and ``image`` fields of :class:`FitConfig` do not apply to photographs.
"""

from __future__ import annotations

from dataclasses import dataclass

from roomlight.errors import RoomlightError
from roomlight.fitting.inverse.config import FitConfig

__all__ = ["PhotoFitConfig", "PHOTO_PRESETS", "photo_config"]


@dataclass(frozen=True)
class PhotoFitConfig(FitConfig):
    """Every knob of a photo fit (the inherited fields: :class:`FitConfig`)."""

    iterations: int = 1000                #: optimisation steps
    spp: int = 128                        #: samples per pixel of the fitted render
    lambda_log: float = 0.01              #: weight of the log-space image term
    lambda_rep: float = 1.0               #: weight of the repulsion term (objects + view-frustum points)
    grad_clip: float = 0.0                #: global gradient-norm clip; 0 = off (the latent step clip replaces it)
    latent_step_clip: float = 0.1         #: largest norm of one step of z (0 = off)
    z_prior: float = 1e-4                 #: weight w of the Gaussian prior w * 0.5 |z|^2
    z_anchor: float = 0.0                 #: weight of a pull 0.5 |z - z_start|^2 towards the fit's start (0 = off)
    geometry_size: int = 1024             #: longest side (px) of the depth mesh
    render_size: int = 640                #: longest side (px) of the rendered and fitted image
    edge_tolerance: float = 0.05          #: relative depth jump that cuts a triangle of the depth mesh
    min_object_fraction: float = 2e-4     #: objects smaller than this fraction of the image are ignored
    lambda_frustum: float = 1.0           #: weight of the frustum radiance term (emitter vs unmasked photo)
    lambda_frustum_depth: float = 1.0     #: weight of the frustum depth term (2.5D emitters only)
    frustum_pixels: int = 4096            #: unmasked pixels in the frustum terms (a fixed random subset)
    frustum_points: int = 512             #: free-space points in the view frustum for the repulsion term
    free_space_fraction: float = 0.9      #: free-space points lie up to this fraction of each pixel's distance
    contain: bool = True                  #: a floor under the 2.5D light's depth keeps that free space and the objects inside
    surface_floor: str = "neighbours"     #: that floor under the visible room: neighbours (every point enclosed) or cell (its own cell only)
    init: str = "auto"                    #: start of z: view (view encoder), samples (paper), zero; auto = view if the prior has one
    init_samples: int = 16                #: N(0, I) draws; the one with the largest room starts the fit
    placement_steps: int = 200            #: steps placing the camera and objects inside the initial room
    start_exposure_ev: float = 0.0        #: stops added to the light's starting level (matched to the photo's background)
    checkpoint_every: int = 25            #: save the fit's state every this many iterations (0 = never)
    albedo_prior: float = 0.0             #: weight of the log-normal reflectance prior on the objects' mean albedo (0 = off)
    albedo_prior_mean: float = 0.3        #: the typical mean albedo over R, G, B that prior is centred on
    albedo_prior_average: str = "arithmetic"  #: which mean over R, G, B it holds: arithmetic or geometric (see docs/photo.md)
    albedo_range: tuple[float, float] = (0.0, 1.0)  #: the objects' albedo is held inside this range ((0.03, 0.9): real surfaces')
    metal_band: float = 0.0               #: weight of the real-metal bound: no metal's mean albedo inside metal_band_range (0 = off)
    metal_band_range: tuple[float, float] = (0.06, 0.45)  #: mean albedos no real metal has (above a clear coat's, below any pure metal's)
    room_albedo: float = 1.0              #: weight of the visible room's albedo bound (fitting/photo/room_albedo.py; 0 = off)
    room_albedo_range: tuple[float, float] = (0.03, 0.9)  #: the albedos the visible room's surfaces may have
    room_albedo_points: int = 512         #: visible room points the bound is checked at (a fixed random subset)
    room_albedo_trim: float = 0.1         #: share of those points breaking the bound most that are left out (lamps, screens)
    level_bracket_trim: float = 0.1       #: share of the visible points left out at each end of the reported level bracket
    room_albedo_moves: str = "light"      #: what the bound may move: the whole light, or its exposure (its brightness) only
    shadow_receivers: bool = False        #: fit the surface each object stands on as a receiver of its shadow (fitting/photo/receivers.py)
    lambda_receivers: float = 1.0         #: weight of the receivers' image term
    receiver_radius: float = 0.5          #: a receiver reaches this many object sizes (image bounding box) from its object
    receiver_min_up: float = 0.7          #: a receiver pixel's normal has at least this cosine with the room's up
    #: the white balance beside the exposure (FitConfig.white_balance) is off for photos: measured on the
    #: photo benchmark it raised the probes' colour error by 1.4-3.0 degrees and gained nothing
    #: (docs/results.md#white-balance); --set white_balance=true turns it on
    white_balance: bool = False
    probe_count: int = 4                  #: probe positions on the object surfaces (probes.png)
    probe_size: float = 0.06              #: probe radius as a fraction of its distance to the camera
    probe_resolution: int = 96            #: pixels of each probe close-up (square)
    probe_spp: int = 128                  #: samples per pixel of the probe and final renders

    def validate(self) -> "PhotoFitConfig":
        """Refuse settings that cannot work (sizes, counts, fractions out of range)."""
        checks = [
            (self.iterations >= 0, "iterations must be >= 0"),
            (self.spp >= 1 and self.probe_spp >= 1, "spp and probe_spp must be >= 1"),
            (self.geometry_size >= 8 and self.render_size >= 8, "geometry_size and render_size must be >= 8 px"),
            (self.edge_tolerance > 0, "edge_tolerance must be > 0"),
            (0 <= self.min_object_fraction < 1, "min_object_fraction must be in [0, 1)"),
            (self.frustum_pixels >= 0 and self.frustum_points >= 0, "frustum_pixels and frustum_points must be >= 0"),
            (0 < self.free_space_fraction < 1, "free_space_fraction must be in (0, 1)"),
            (self.surface_floor in ("neighbours", "cell"), "surface_floor must be neighbours or cell"),
            (self.init_samples >= 1, "init_samples must be >= 1"),
            (self.init in ("auto", "view", "samples", "zero"), "init must be one of auto, view, samples, zero"),
            (self.placement_steps >= 0, "placement_steps must be >= 0"),
            (self.latent_step_clip >= 0 and self.grad_clip >= 0, "latent_step_clip and grad_clip must be >= 0"),
            (self.z_anchor >= 0, "z_anchor must be >= 0"),
            (self.probe_count >= 0 and self.probe_resolution >= 8, "probe_count >= 0 and probe_resolution >= 8"),
            (0 < self.probe_size < 1, "probe_size must be in (0, 1)"),
            (self.albedo_prior >= 0, "albedo_prior must be >= 0"),
            (self.metal_band >= 0, "metal_band must be >= 0"),
            (len(self.metal_band_range) == 2 and 0 < self.metal_band_range[0] < self.metal_band_range[1] < 1,
             "metal_band_range must be [lo, hi] with 0 < lo < hi < 1"),
            (0 < self.albedo_prior_mean < 1, "albedo_prior_mean must be in (0, 1)"),
            (self.albedo_prior_average in ("geometric", "arithmetic"),
             "albedo_prior_average must be geometric or arithmetic"),
            (self.room_albedo >= 0 and self.room_albedo_points >= 0, "room_albedo and room_albedo_points must be >= 0"),
            (len(self.room_albedo_range) == 2 and 0 < self.room_albedo_range[0] < self.room_albedo_range[1],
             "room_albedo_range must be [lo, hi] with 0 < lo < hi"),
            (0 <= self.room_albedo_trim < 1, "room_albedo_trim must be in [0, 1)"),
            (0 <= self.level_bracket_trim < 0.5, "level_bracket_trim must be in [0, 0.5)"),
            (self.room_albedo_moves in ("exposure", "light"), "room_albedo_moves must be exposure or light"),
            (self.lambda_receivers >= 0 and self.receiver_radius > 0, "lambda_receivers >= 0 and receiver_radius > 0"),
            (-1 <= self.receiver_min_up < 1, "receiver_min_up must be in [-1, 1)"),
            (len(self.albedo_range) == 2 and 0.0 <= self.albedo_range[0] < 0.5 < self.albedo_range[1] <= 1.0,
             "albedo_range must be [lo, hi] with 0 <= lo < 0.5 < hi <= 1 (the fit starts at 0.5)"),
        ]
        for ok, message in checks:
            if not ok:
                raise RoomlightError(f"photo fit settings: {message}")
        return self


#: ``paper``: the paper's real-image settings; ``fast``: well under a minute on a 2-core CPU;
#: ``balanced``: between the two (2.5x ``fast``'s steps at twice the samples, a photo's longest side
#: fitted at up to 256 px: 5-20x its rendering work, depending on the photo's size).
PHOTO_PRESETS: dict[str, PhotoFitConfig] = {
    "paper": PhotoFitConfig(),
    "fast": PhotoFitConfig(iterations=120, spp=8, geometry_size=256, render_size=128, eval_every=10,
                           eval_spp=16, init_samples=8, probe_spp=64, probe_resolution=64),
    "balanced": PhotoFitConfig(iterations=300, spp=16, geometry_size=512, render_size=256, eval_every=20,
                               eval_spp=32, init_samples=16, probe_spp=128, probe_resolution=96),
}


def photo_config(preset: str = "paper", **overrides) -> PhotoFitConfig:
    """The settings of ``preset`` with some fields changed (an override of None keeps the preset's value)."""
    if preset not in PHOTO_PRESETS:
        raise RoomlightError(f"unknown photo preset {preset!r}; choose one of {', '.join(PHOTO_PRESETS)}")
    cfg = PHOTO_PRESETS[preset].override(**{k: v for k, v in overrides.items() if v is not None})
    return cfg.validate()
