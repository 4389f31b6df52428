"""Panorama depth from a perspective depth estimator: 12 tangent views, fused, put in metres.

:func:`estimate_panorama_depth` tone maps the panorama (:class:`~roomlight.datagen.prepare.tonemap.DisplayMap`),
cuts the 12 icosahedron views (:mod:`roomlight.datagen.prepare.views`), runs the estimator on each,
fuses the predictions (:func:`roomlight.datagen.prepare.fusion.fuse_views`) and sets the scale: a metric
estimator's scale is kept; otherwise the depth is scaled so that the floor found in the lower
hemisphere (:func:`~roomlight.datagen.prepare.fusion.floor_distance`) lies ``camera_height`` metres
below the capture point.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from roomlight.errors import RoomlightError
from roomlight.datagen.prepare.estimators import estimator_depth_type, estimator_kind, run_estimator
from roomlight.datagen.prepare.fusion import FusionResult, floor_distance, fuse_views
from roomlight.datagen.prepare.tonemap import DisplayMap
from roomlight.datagen.prepare.views import cut_views, default_view_size

__all__ = ["DepthResult", "estimate_panorama_depth", "DEFAULT_CAMERA_HEIGHT"]

#: Height of a tripod-mounted camera above the floor, metres (``--camera-height``).
DEFAULT_CAMERA_HEIGHT = 1.6


@dataclass
class DepthResult:
    """Attributes:
        depth: (H, W) float32 radial depth, metres.
        kind, depth_type: what the estimator predicts.
        fusion: the alignment (:class:`~roomlight.datagen.prepare.fusion.FusionResult`).
        floor_m: the camera's height above the floor in the written depth.
        scale: factor applied to the fused depth (1 for a metric estimator).
        view_size, fov_deg: the views.
    """

    depth: np.ndarray
    kind: str
    depth_type: str
    fusion: FusionResult
    floor_m: float
    scale: float
    view_size: int
    fov_deg: float

    def summary(self) -> dict:
        return {"kind": self.kind, "depth_type": self.depth_type, "views": len(self.fusion.scales),
                "view_size": self.view_size, "view_fov_deg": self.fov_deg, "floor_m": round(self.floor_m, 6),
                "scale": self.scale, "scaled_to": "metric" if self.kind == "metric" else "camera height",
                **self.fusion.summary()}


def estimate_panorama_depth(radiance: np.ndarray, estimator, *, camera_height: float = DEFAULT_CAMERA_HEIGHT,
                            view_size: int | None = None, fov_deg: float = 90.0) -> DepthResult:
    """Radial depth (metres) of a radiance panorama.

    Args:
        radiance: (H, W, 3) linear radiance, W = 2H (inpaint the nadir first: the estimator sees it).
        estimator: a per-view estimator (:mod:`roomlight.datagen.prepare.estimators`).
        camera_height: metres between the floor and the capture point, used when the estimator
            is not metric.
        view_size: square view size; default :func:`~roomlight.datagen.prepare.views.default_view_size`.
        fov_deg: the views' field of view (90 deg: the 12 views overlap by about a third).
    """
    rad = np.asarray(radiance, np.float64)
    h = rad.shape[0]
    if not camera_height > 0:
        raise RoomlightError(f"camera height must be > 0 metres, got {camera_height}")
    kind, depth_type = estimator_kind(estimator), estimator_depth_type(estimator)
    size = int(view_size) if view_size else default_view_size(h, fov_deg)
    display = DisplayMap.fit(rad).forward(rad)
    views = cut_views(display, size, fov_deg)
    depths, valids = [], []
    for v in views:
        d, ok = run_estimator(estimator, v)
        depths.append(d)
        valids.append(ok)
    fusion = fuse_views(views, depths, valids, h, kind=kind, depth_type=depth_type)
    floor = floor_distance(fusion.depth)
    scale = 1.0 if kind == "metric" else camera_height / floor
    depth = (fusion.depth * scale).astype(np.float32)
    return DepthResult(depth, kind, depth_type, fusion, float(floor * scale), float(scale), size, float(fov_deg))
