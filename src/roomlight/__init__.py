"""roomlight: spatially-varying indoor illumination as 2.5D area lights.

The package is organised by concept, bottom layer first (docs/architecture.md has the data's
path through them; ``tests/test_layers.py`` keeps the order):

- :mod:`roomlight.errors`     the exception types every layer raises
- :mod:`roomlight.core.color`      luminance, log-average, middle grey, display gamma and mapping
- :mod:`roomlight.core.config`     the settings base: strict to_dict / from_dict / override
- :mod:`roomlight.core.geometry`   equirectangular conventions, projections, spherical padding, rotations
- :mod:`roomlight.core.io`         panorama / depth / mesh files and previews
- :mod:`roomlight.core.emitter`    emitter kinds: the 2.5D area light, env map, sphere proxy; bundles
- :mod:`roomlight.core.render`     Mitsuba variant, ``EmitterScene``, the torch <-> Dr.Jit bridge, cameras
- :mod:`roomlight.fitting.scene`      scene descriptions (objects, views, targets) and their Mitsuba form
- :mod:`roomlight.prior.model`      the panoramic VAE prior, normalisation, checkpoints and run folders
- :mod:`roomlight.prior.losses`     the prior's training losses
- :mod:`roomlight.prior.latent_fit`        latent fitting: the latent that reproduces a panorama (``fit-pano``)
- :mod:`roomlight.core.examples`   the built-in analytic example room
- :mod:`roomlight.prior.data`       panorama datasets, caches, splits, statistics, augmentation
- :mod:`roomlight.fitting.inverse`    inverse rendering: a scene's light from an image (``roomlight fit``)
- :mod:`roomlight.datagen.synth`      procedural rooms rendered into HDR panoramas with depth
- :mod:`roomlight.prior.eval`       metrics and evaluation of the prior, sample figures and panels
- :mod:`roomlight.evaluation.bench`      the synthetic benchmark: build, run, score, tables and report
- :mod:`roomlight.prior.train`      training the prior: configuration, loop, resumable checkpoints
- :mod:`roomlight.parallax`   the parallax figure: 2.5D area light against an env map
- :mod:`roomlight.demo`       the end-to-end demo behind ``roomlight demo``
- :mod:`roomlight.cli`        the ``roomlight`` command line

Heavy dependencies (Mitsuba, Dr.Jit) are imported lazily, so ``import roomlight`` is cheap.
"""

__version__ = "0.1.0"

from roomlight.errors import RoomlightError  # noqa: E402

__all__ = ["RoomlightError", "__version__"]
