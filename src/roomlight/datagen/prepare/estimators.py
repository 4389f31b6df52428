"""Per-view depth estimators: the protocol, an offline synthetic one, and a MoGe adapter.

An estimator is a callable ``estimator(view) -> depth`` or ``-> (depth, valid)`` taking a
:class:`roomlight.datagen.prepare.views.View` (its ``image`` is (h, w, 3) float32 display values in
[0, 1]) and returning (h, w) depth and optionally an (h, w) bool validity mask (pixels it
cannot judge: sky, mirrors; non-finite or non-positive depth counts as invalid too). Two
optional attributes say what the numbers mean:

- ``kind``: ``metric`` (metres), ``scale`` (true depth = s x depth, s unknown per view) or
  ``affine`` (true depth = s x depth + t, s and t unknown per view); default ``scale``;
- ``depth_type``: ``z`` (distance along the view's axis, what most networks predict) or
  ``distance`` (along each pixel's ray); default ``z``.

:class:`SyntheticEstimator` returns the *true* depth of the panorama, distorted per view the
way a network's prediction is (an unknown scale and shift, a smooth bias field, pixel noise),
so the fusion is exercised as with a real network, offline. It needs the truth: the panorama's
own depth channel, or a side file (``roomlight prepare --truth DIR``).

:class:`MoGeEstimator` runs MoGe (Wang et al. 2025) when its package and weights are installed.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch

from roomlight.errors import RoomlightError
from roomlight.core.geometry.equirect import direction_to_uv
from roomlight.datagen.prepare.views import View, view_plane_coordinates

__all__ = ["ESTIMATOR_KINDS", "DEPTH_TYPES", "SyntheticEstimator", "MoGeEstimator", "EstimatorSpec",
           "resolve_estimator", "run_estimator", "estimator_kind", "estimator_depth_type"]

ESTIMATOR_KINDS = ("metric", "scale", "affine")
DEPTH_TYPES = ("z", "distance")


def estimator_kind(est) -> str:
    kind = getattr(est, "kind", "scale")
    if kind not in ESTIMATOR_KINDS:
        raise RoomlightError(f"depth estimator {est!r}: kind must be one of {ESTIMATOR_KINDS}, got {kind!r}")
    return kind


def estimator_depth_type(est) -> str:
    t = getattr(est, "depth_type", "z")
    if t not in DEPTH_TYPES:
        raise RoomlightError(f"depth estimator {est!r}: depth_type must be one of {DEPTH_TYPES}, got {t!r}")
    return t


def run_estimator(est, view: View) -> tuple[np.ndarray, np.ndarray]:
    """Call an estimator on one view and check its answer: (h, w) float64 depth, (h, w) bool valid."""
    out = est(view)
    if isinstance(out, tuple):
        if len(out) != 2:
            raise RoomlightError(f"depth estimator returned {len(out)} values for view {view.index}; "
                                 "expected depth or (depth, valid)")
        depth, valid = out
        valid = np.asarray(valid, bool)
    else:
        depth, valid = out, None
    if isinstance(depth, torch.Tensor):
        depth = depth.detach().cpu().numpy()
    depth = np.asarray(depth, np.float64)
    if depth.shape != view.size:
        raise RoomlightError(f"depth estimator returned shape {depth.shape} for view {view.index} of size {view.size}")
    ok = np.isfinite(depth) & (depth > 0)
    if valid is not None:
        if valid.shape != view.size:
            raise RoomlightError(f"depth estimator returned a mask of shape {valid.shape} for a view of size {view.size}")
        ok &= valid
    return np.where(ok, depth, 1.0), ok


@dataclass
class SyntheticEstimator:
    """The truth, distorted per view like a network's prediction (see the module docstring).

    Per view k (seeded by ``seed`` and k): true planar depth z (nearest panorama pixel, so depth
    edges stay sharp) becomes ``z exp(b(x, y) + n)``, with ``b`` a sum of three random plane
    waves of at most half a period across the view scaled to ``max |b| = bias`` and ``n``
    Gaussian pixel noise of standard deviation ``noise``; then

    - ``affine``: ``(z' - t) / s``, s log-uniform in ``scale_range``, t uniform in
      ``+-shift x min(z')`` (so the prediction stays positive);
    - ``scale``: ``z' / s``;
    - ``metric``: ``z' exp(e)``, e uniform in ``+-metric_jitter`` (metric networks disagree
      between views by a few percent too).

    Args:
        truth: (H, W) true radial depth of the panorama, metres.
    """

    truth: np.ndarray
    kind: str = "affine"
    noise: float = 0.01
    bias: float = 0.02
    scale_range: tuple[float, float] = (0.5, 2.0)
    shift: float = 0.5
    metric_jitter: float = 0.05
    seed: int = 0
    depth_type: str = "z"

    def __post_init__(self):
        if self.kind not in ESTIMATOR_KINDS:
            raise RoomlightError(f"synthetic estimator: kind must be one of {ESTIMATOR_KINDS}, got {self.kind!r}")
        t = np.asarray(self.truth, np.float64)
        if t.ndim != 2 or t.shape[1] != 2 * t.shape[0]:
            raise RoomlightError(f"synthetic estimator: the true depth must be (H, 2H), got {t.shape}")
        if not (np.isfinite(t).all() and (t > 0).all()):
            raise RoomlightError("synthetic estimator: the true depth must be finite and > 0")
        self.truth = t

    def true_distance(self, view: View) -> np.ndarray:
        """(h, w) true radial depth along the view's pixel rays (nearest panorama pixel)."""
        h, w = self.truth.shape
        u, v = direction_to_uv(torch.from_numpy(np.asarray(view.directions, np.float64)))
        j = np.floor(u.numpy() * w).astype(np.int64) % w
        i = np.clip(np.floor(v.numpy() * h).astype(np.int64), 0, h - 1)
        return self.truth[i, j]

    def distortion(self, index: int) -> tuple[float, float]:
        """View ``index``'s scale s and shift factor f: the prediction is (z' - f min z') / s
        (metric: s = exp(-e), f = 0; scale: f = 0)."""
        rng = np.random.default_rng([int(self.seed) & 0x7FFFFFFF, int(index), 1])
        if self.kind == "metric":
            return math.exp(-rng.uniform(-self.metric_jitter, self.metric_jitter)), 0.0
        lo, hi = self.scale_range
        s = math.exp(rng.uniform(math.log(lo), math.log(hi)))
        return s, (rng.uniform(-self.shift, self.shift) if self.kind == "affine" else 0.0)

    def __call__(self, view: View) -> np.ndarray:
        rng = np.random.default_rng([int(self.seed) & 0x7FFFFFFF, int(view.index)])
        z = self.true_distance(view) * view.cos_to_axis()
        x, y = view_plane_coordinates(*view.size)
        field = np.zeros_like(x)
        for _ in range(3):
            f = rng.uniform(-0.5, 0.5, 2)  # cycles across the half-width: at most half a period
            field += rng.uniform(0.5, 1.0) * np.cos(math.pi * (f[0] * x + f[1] * y) + rng.uniform(0, 2 * math.pi))
        field *= self.bias / max(np.abs(field).max(), 1e-12)
        zd = z * np.exp(field + rng.normal(0.0, self.noise, z.shape))
        s, f = self.distortion(view.index)
        return (zd - f * float(zd.min())) / s


class MoGeEstimator:
    """MoGe (``moge`` package, from Microsoft's MoGe repository) on each view, with the view's known field of view.

    MoGe-2 checkpoints predict metric depth (``kind = metric``); MoGe-1 checkpoints predict depth
    up to scale (``kind = scale``). The weights are a local ``model.pt`` (``weights`` or the
    ``ROOMLIGHT_MOGE_WEIGHTS`` environment variable); nothing is downloaded.
    """

    depth_type = "z"

    def __init__(self, weights: str | os.PathLike | None = None, device: str | None = None,
                 resolution_level: int = 9):
        try:
            import moge  # noqa: F401
        except ImportError as e:
            raise RoomlightError(
                "--depth moge needs the MoGe package (pip install from Microsoft's MoGe repository, "
                "github.com/microsoft/MoGe) and a checkpoint model.pt; without them use --depth synthetic "
                "(tests) or --depth MODULE:FUNCTION") from e
        path = weights or os.environ.get("ROOMLIGHT_MOGE_WEIGHTS")
        if not path:
            raise RoomlightError("--depth moge needs its weights: pass --depth moge:/path/to/model.pt or set "
                                 "ROOMLIGHT_MOGE_WEIGHTS (they are not downloaded)")
        if not Path(path).is_file():
            raise RoomlightError(f"MoGe weights {path}: file does not exist (expected a MoGe checkpoint model.pt)")
        checkpoint = torch.load(path, map_location="cpu", weights_only=True)
        version = "v2" if "scale_head" in checkpoint.get("model_config", {}) else "v1"
        try:
            if version == "v2":
                from moge.model.v2 import MoGeModel
            else:
                from moge.model.v1 import MoGeModel
        except ImportError as e:
            raise RoomlightError(f"MoGe weights {path} are a {version} checkpoint, which this moge package cannot load "
                                 f"({e})") from e
        self.kind = "metric" if version == "v2" else "scale"
        self.device = torch.device(device or ("cuda" if torch.cuda.is_available() else "cpu"))
        self.model = MoGeModel.from_pretrained(path).to(self.device).eval()
        self.resolution_level = int(resolution_level)
        self.name = f"moge-{version}"

    def __call__(self, view: View):
        img = torch.from_numpy(np.ascontiguousarray(view.image.transpose(2, 0, 1))).float().to(self.device)
        out = self.model.infer(img, fov_x=float(view.fov_deg), apply_mask=False,
                               resolution_level=self.resolution_level)
        depth = out["depth"].float().cpu().numpy()
        mask = out["mask"].cpu().numpy().astype(bool) if "mask" in out else np.ones_like(depth, bool)
        return depth, mask


@dataclass
class EstimatorSpec:
    """What ``--depth`` asked for: ``make(truth, seed)`` gives the estimator for one panorama.

    Attributes:
        name: the option's text.
        needs_truth: the estimator is built per panorama from its true depth (synthetic).
        keep: keep the input's own depth (``--depth keep``); no estimator.
    """

    name: str
    needs_truth: bool = False
    keep: bool = False
    _factory: object = None
    _shared: object = None

    def make(self, truth: np.ndarray | None = None, seed: int = 0):
        if self.keep:
            raise RoomlightError("--depth keep uses the input's depth; there is no estimator")
        if self.needs_truth:
            if truth is None:
                raise RoomlightError("the synthetic estimator needs the true depth (a Z channel or --truth DIR)")
            return self._factory(truth, seed)
        if self._shared is None:  # built once per process: a network is loaded once
            self._shared = self._factory()
        return self._shared


def resolve_estimator(spec) -> EstimatorSpec:
    """``keep``, ``synthetic[:affine|scale|metric]``, ``moge[:WEIGHTS]``, ``MODULE:FUNCTION`` or a callable."""
    from roomlight.datagen.prepare.inpainters import load_callable

    if callable(spec):
        est = spec
        return EstimatorSpec(getattr(spec, "__name__", "callable"), _factory=lambda: est)
    text = str(spec).strip()
    name, _, arg = text.partition(":")
    if name == "keep" and not arg:
        return EstimatorSpec(text, keep=True)
    if name == "synthetic":
        kind = arg or "affine"
        if kind not in ESTIMATOR_KINDS:
            raise RoomlightError(f"--depth synthetic:{kind}: the kind must be one of {', '.join(ESTIMATOR_KINDS)}")
        return EstimatorSpec(text, needs_truth=True,
                             _factory=lambda truth, seed: SyntheticEstimator(truth, kind=kind, seed=seed))
    if name == "moge":
        return EstimatorSpec(text, _factory=lambda: MoGeEstimator(arg or None))
    if arg:
        obj = load_callable(text, "depth estimator")
        # a class (or factory) taking no argument is instantiated; a plain function is the estimator
        factory = obj if isinstance(obj, type) else (lambda: obj)
        return EstimatorSpec(text, _factory=factory)
    raise RoomlightError(f"unknown depth estimator {text!r}: use keep, synthetic[:affine|scale|metric], "
                         "moge[:WEIGHTS] or MODULE:FUNCTION")
