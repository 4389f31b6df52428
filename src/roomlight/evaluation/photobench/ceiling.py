"""The prior's own ceiling on a photo: the best the prior can do *given the whole room*.

The photo's oracle panorama (the room captured at the oracle centre, ``truth/oracle.exr``) is
fitted by the prior's latent (:func:`roomlight.prior.latent_fit.latent.fit_latent`, radiance and depth, from
the encoder's mean with depth weighted 3x and the peak term: :data:`CEILING_FIT`), and that decoded panorama is
the light, in the oracle's frame. Comparing it with ``oracle`` measures what the prior's latent
space loses; comparing the photo fits with it measures what fitting from one photograph loses.
"""

from __future__ import annotations

from pathlib import Path

from roomlight.evaluation.photobench import case as fmt

__all__ = ["CEILING", "CEILING_FIT", "prior_ceiling_latent", "prior_ceiling_light"]

#: The benchmark's name of this reference.
CEILING = "prior-ceiling"
#: Settings of the latent fit (LatentFitConfig fields).
#: The recommended fit of a panorama with depth (docs/results.md, "The bundled prior"): the encoder's
#: mean as the start, depth weighted 3x, and the peak term, which keeps the strongest light within half a
#: stop (without it the fit misses it by 0.57 stops on average on held-out rooms).
CEILING_FIT = {"steps": 1500, "init_from_encoder": True, "depth_weight": 3.0, "peak_weight": 0.03}


def prior_ceiling_latent(case_dir, model, truth=None):
    """The prior's latent fitted to the case's oracle panorama.

    Returns:
        (result, exposure_factor, frame): the :class:`~roomlight.prior.latent_fit.latent.LatentFitResult`
        of one panorama (``z`` (1, latent), ``radiance`` (1, 3, H, W) and ``depth`` (1, 1, H, W) decoded at
        it, in the calibrated units the fit saw), the factor that brings that radiance back to the
        oracle's units, and the oracle's (4, 4) light-from-camera frame the room stands in.
    """
    from roomlight.prior.data.dataset import load_training_pair
    from roomlight.errors import RoomlightError
    from roomlight.prior.latent_fit.latent import LatentFitConfig, fit_latent
    from roomlight.evaluation.photobench.scoring import oracle_light

    if model is None:
        raise RoomlightError(f"{CEILING} needs a prior (--model)")
    oracle = oracle_light(case_dir, "mesh", truth)
    rad, dep, info = load_training_pair(Path(case_dir) / fmt.ORACLE, model.config.resolution, calibrate=True)
    device = next(model.parameters()).device
    res = fit_latent(model, rad[None].to(device), dep[None].to(device), LatentFitConfig(**CEILING_FIT))
    return res, float(info["exposure_factor"]), oracle.frame


def prior_ceiling_light(case_dir, model, truth=None):
    """The prior's best approximation of the case's oracle panorama, as a 2.5D
    :class:`~roomlight.core.light.Light` in the oracle's frame."""
    from roomlight.core.light import Light

    res, exposure_factor, frame = prior_ceiling_latent(case_dir, model, truth)
    radiance = (res.radiance[0] * exposure_factor).permute(1, 2, 0)
    return Light(radiance, res.depth[0, 0], "mesh", frame)
