"""``roomlight prepare``: real HDR captures made into training data (nadir inpainting, panorama depth).

- :mod:`~roomlight.prepare.tonemap`: the display mapping shown to networks, and its exact inverse;
- :mod:`~roomlight.prepare.nadir`: finding and inpainting the tripod blind spot;
- :mod:`~roomlight.prepare.inpainters`: OpenCV (built in), LaMa, your own;
- :mod:`~roomlight.prepare.views`: the 12 tangent views;
- :mod:`~roomlight.prepare.estimators`: per-view depth estimators (synthetic, MoGe, your own);
- :mod:`~roomlight.prepare.fusion`: the global consistency solve and the floor;
- :mod:`~roomlight.prepare.depth`: views -> estimates -> fused depth in metres;
- :mod:`~roomlight.prepare.dataset`: the folder-to-dataset driver behind the command.

See docs/prepare.md.
"""

from roomlight.prepare.depth import DEFAULT_CAMERA_HEIGHT, DepthResult, estimate_panorama_depth
from roomlight.prepare.estimators import MoGeEstimator, SyntheticEstimator, resolve_estimator
from roomlight.prepare.inpainters import LamaInpainter, OpenCVInpainter, resolve_inpainter
from roomlight.prepare.nadir import NadirResult, detect_nadir_cap, inpaint_nadir
from roomlight.prepare.tonemap import DisplayMap

__all__ = ["DEFAULT_CAMERA_HEIGHT", "DepthResult", "DisplayMap", "LamaInpainter", "MoGeEstimator", "NadirResult",
           "OpenCVInpainter", "SyntheticEstimator", "detect_nadir_cap", "estimate_panorama_depth", "inpaint_nadir",
           "resolve_estimator", "resolve_inpainter"]
