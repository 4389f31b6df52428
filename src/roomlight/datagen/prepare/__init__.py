"""``roomlight prepare``: real HDR captures made into training data (nadir inpainting, panorama depth).

- :mod:`~roomlight.datagen.prepare.tonemap`: the display mapping shown to networks, and its exact inverse;
- :mod:`~roomlight.datagen.prepare.nadir`: finding and inpainting the tripod blind spot;
- :mod:`~roomlight.datagen.prepare.inpainters`: OpenCV (built in), LaMa, your own;
- :mod:`~roomlight.datagen.prepare.views`: the 12 tangent views;
- :mod:`~roomlight.datagen.prepare.estimators`: per-view depth estimators (synthetic, MoGe, your own);
- :mod:`~roomlight.datagen.prepare.fusion`: the global consistency solve and the floor;
- :mod:`~roomlight.datagen.prepare.depth`: views -> estimates -> fused depth in metres;
- :mod:`~roomlight.datagen.prepare.dataset`: the folder-to-dataset driver behind the command.

See docs/prepare.md.
"""

from roomlight.datagen.prepare.depth import DEFAULT_CAMERA_HEIGHT, DepthResult, estimate_panorama_depth
from roomlight.datagen.prepare.estimators import MoGeEstimator, SyntheticEstimator, resolve_estimator
from roomlight.datagen.prepare.inpainters import LamaInpainter, OpenCVInpainter, resolve_inpainter
from roomlight.datagen.prepare.nadir import NadirResult, detect_nadir_cap, inpaint_nadir
from roomlight.datagen.prepare.tonemap import DisplayMap

__all__ = ["DEFAULT_CAMERA_HEIGHT", "DepthResult", "DisplayMap", "LamaInpainter", "MoGeEstimator", "NadirResult",
           "OpenCVInpainter", "SyntheticEstimator", "detect_nadir_cap", "estimate_panorama_depth", "inpaint_nadir",
           "resolve_estimator", "resolve_inpainter"]
