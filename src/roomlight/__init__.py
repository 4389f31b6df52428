"""roomlight: spatially-varying indoor illumination as 2.5D area lights.

The package is organised by concept:

- :mod:`roomlight.geometry`  equirectangular conventions, projections, spherical padding, rotations
- :mod:`roomlight.io`        panorama / depth / mesh files and previews
- :mod:`roomlight.emitter`   the 2.5D area light, env-map and sphere-proxy emitters
- :mod:`roomlight.render`    Mitsuba variant selection, scenes, the torch <-> Dr.Jit bridge

Heavy dependencies (Mitsuba, Dr.Jit) are imported lazily, so ``import roomlight`` is cheap.
"""

__version__ = "0.1.0"

from roomlight.errors import RoomlightError  # noqa: E402

__all__ = ["RoomlightError", "__version__"]
