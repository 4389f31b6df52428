"""Monocular geometry estimators: depth, intrinsics and normals from the photograph alone.

An estimator is any Python callable ``estimator(image) -> result`` where ``image`` is the photo
as (H, W, 3) float32 sRGB-encoded values in [0, 1] (what such networks are trained on) and
``result`` is a :class:`GeometryEstimate`, or a tuple ``(depth, intrinsics)`` /
``(depth, intrinsics, normals)`` with

- ``depth``: (H, W) metres, z-depth (build a :class:`GeometryEstimate` to say ``radial``);
- ``intrinsics``: a :class:`~roomlight.fitting.photo.camera.PhotoCamera`, ``(fx, fy, cx, cy)`` in pixels,
  a 3 x 3 pixel matrix, or None when unknown;
- ``normals``: (H, W, 3) unit normals in roomlight's camera frame (x right, y up, z towards the
  viewer), or None.

``roomlight fit-photo --estimator`` takes ``moge`` (the adapter below) or ``module:function``.
The ``moge`` adapter runs MoGe-2 when the ``moge`` package is importable and its weights are on
this machine (a local checkpoint file in ``$ROOMLIGHT_MOGE_MODEL``, or a model already in the
Hugging Face cache); it never downloads anything.
"""

from __future__ import annotations

import importlib
import importlib.util
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from roomlight.errors import RoomlightError
from roomlight.fitting.photo.camera import PhotoCamera

__all__ = ["GeometryEstimate", "MoGeEstimator", "MOGE_DEFAULT_MODEL", "moge_available", "resolve_estimator",
           "estimate_geometry", "as_estimate"]

#: The MoGe-2 checkpoint with metric scale and normals (a Hugging Face repository id).
MOGE_DEFAULT_MODEL = "Ruicheng/moge-2-vitl-normal"


@dataclass
class GeometryEstimate:
    """What an estimator returns (see the module docstring)."""

    depth: np.ndarray
    intrinsics: PhotoCamera | None = None
    normals: np.ndarray | None = None
    kind: str = "z"
    name: str = "estimator"


def _intrinsics(value, width: int, height: int) -> PhotoCamera | None:
    if value is None or isinstance(value, PhotoCamera):
        return value
    a = np.asarray(value, dtype=np.float64)
    if a.shape == (4,):
        return PhotoCamera(width, height, *map(float, a))
    if a.shape == (3, 3):
        return PhotoCamera(width, height, float(a[0, 0]), float(a[1, 1]), float(a[0, 2]), float(a[1, 2]))
    raise RoomlightError(f"estimator: intrinsics must be (fx, fy, cx, cy), a 3x3 matrix or a PhotoCamera, "
                         f"got shape {a.shape}")


def as_estimate(result, width: int, height: int, name: str = "estimator") -> GeometryEstimate:
    """Normalise an estimator's return value (a GeometryEstimate or a tuple) and check its shapes."""
    if isinstance(result, GeometryEstimate):
        est = result
    elif isinstance(result, (tuple, list)) and len(result) in (2, 3):
        est = GeometryEstimate(np.asarray(result[0]), result[1], result[2] if len(result) == 3 else None, name=name)
    else:
        raise RoomlightError(f"{name}: expected (depth, intrinsics[, normals]) or a GeometryEstimate, "
                             f"got {type(result).__name__}")
    depth = np.asarray(est.depth, dtype=np.float32)
    if depth.shape != (height, width):
        raise RoomlightError(f"{name}: returned depth of shape {depth.shape} for a {width}x{height} image")
    if not (np.isfinite(depth) & (depth > 0)).all():
        raise RoomlightError(f"{name}: returned depth with NaN, infinite or non-positive values")
    normals = None
    if est.normals is not None:
        normals = np.asarray(est.normals, dtype=np.float32)
        if normals.shape != (height, width, 3):
            raise RoomlightError(f"{name}: returned normals of shape {normals.shape}, expected ({height}, {width}, 3)")
    return GeometryEstimate(depth, _intrinsics(est.intrinsics, width, height), normals, est.kind, est.name or name)


def moge_available() -> bool:
    """Whether the ``moge`` package can be imported (its weights are checked when it runs)."""
    try:
        return importlib.util.find_spec("moge") is not None
    except (ImportError, ValueError):
        return False


class MoGeEstimator:
    """MoGe-2 (metric point maps, intrinsics and normals from one image) as an estimator.

    MoGe returns z-depth in metres, intrinsics normalised by the image size (principal point
    and focal lengths as fractions of the width / height, pixel centres at (j + 0.5) / W, which
    is roomlight's pixel convention scaled) and normals in OpenCV's camera frame (x right, y down,
    z forward), which become roomlight's by flipping y and z. Pixels MoGe marks invalid (no
    finite positive depth, e.g. sky) take the largest valid depth.
    """

    name = "moge"

    def __init__(self, model: str | None = None, device: str | None = None):
        self.model_name = model or os.environ.get("ROOMLIGHT_MOGE_MODEL") or MOGE_DEFAULT_MODEL
        self.device = device
        self._model = None

    def _load(self):
        if self._model is not None:
            return self._model
        try:
            from moge.model.v2 import MoGeModel
        except ImportError as exc:
            raise RoomlightError(f"the moge package is not importable ({exc})") from None
        import torch

        try:
            if Path(self.model_name).exists():
                model = MoGeModel.from_pretrained(self.model_name)
            else:  # only what is already in the local cache: never a download
                model = MoGeModel.from_pretrained(self.model_name, local_files_only=True)
        except Exception as exc:
            raise RoomlightError(f"MoGe weights {self.model_name!r} are not on this machine "
                                 f"({str(exc).splitlines()[0] if str(exc) else type(exc).__name__}); set "
                                 "ROOMLIGHT_MOGE_MODEL to a local checkpoint file") from None
        device = self.device or ("cuda" if torch.cuda.is_available() else "cpu")
        self._model = model.to(device).eval()
        return self._model

    def __call__(self, image_srgb: np.ndarray) -> GeometryEstimate:
        import torch

        model = self._load()
        h, w = image_srgb.shape[:2]
        device = next(model.parameters()).device
        x = torch.from_numpy(np.ascontiguousarray(image_srgb, dtype=np.float32)).permute(2, 0, 1).to(device)
        out = model.infer(x, apply_mask=False, use_fp16=device.type == "cuda")
        return self.convert(out, w, h)

    @staticmethod
    def convert(out: dict, width: int, height: int) -> GeometryEstimate:
        """MoGe's ``infer`` output (tensors or arrays) -> a GeometryEstimate in roomlight's conventions."""
        def arr(v):
            return v.detach().float().cpu().numpy() if hasattr(v, "detach") else np.asarray(v, dtype=np.float32)

        depth = arr(out["depth"]).astype(np.float64)
        valid = np.isfinite(depth) & (depth > 0)
        if "mask" in out:
            valid &= arr(out["mask"]).astype(bool)
        if not valid.any():
            raise RoomlightError("moge: no pixel has a valid depth")
        depth = np.where(valid, depth, depth[valid].max()).astype(np.float32)
        k = arr(out["intrinsics"]).astype(np.float64)
        intr = PhotoCamera(width, height, k[0, 0] * width, k[1, 1] * height, k[0, 2] * width, k[1, 2] * height)
        normals = None
        if "normal" in out:
            n = arr(out["normal"]).astype(np.float32)
            normals = n * np.array([1.0, -1.0, -1.0], np.float32)  # OpenCV (x right, y down, z forward) -> ours
        return GeometryEstimate(depth, intr, normals, "z", "moge")


def resolve_estimator(spec):
    """An estimator from ``spec``: a callable (returned as is), ``"moge"``, or ``"module:function"``."""
    if callable(spec):
        return spec
    text = str(spec)
    if text == "moge":
        return MoGeEstimator()
    module, sep, attr = text.partition(":")
    if not sep or not module or not attr:
        raise RoomlightError(f"estimator {text!r}: expected 'moge' or 'module:function'")
    try:
        fn = getattr(importlib.import_module(module), attr)
    except (ImportError, AttributeError) as exc:
        raise RoomlightError(f"estimator {text!r}: cannot import it ({exc})") from None
    if not callable(fn):
        raise RoomlightError(f"estimator {text!r} is not callable")
    return fn


def estimate_geometry(estimator, image_linear: np.ndarray, image_path) -> GeometryEstimate:
    """Run ``estimator`` (see :func:`resolve_estimator`; None: MoGe when installed) on a linear photo.

    Raises a one-line error naming the image when no estimator can run: then ``--depth`` is needed.
    """
    from roomlight.core.color import linear_to_srgb

    need_depth = "pass --depth FILE (per-pixel metric depth: .npy, .exr, or a 16-bit PNG in millimetres)"
    if estimator is None:
        if not moge_available():
            raise RoomlightError(f"{image_path}: no depth map, and no monocular estimator is installed: {need_depth}, "
                                 "or install the moge package (MoGe-2) and its weights")
        estimator = "moge"
    fn = resolve_estimator(estimator)
    h, w = image_linear.shape[:2]
    name = getattr(fn, "name", None) or getattr(fn, "__name__", None) or "estimator"
    try:
        result = fn(linear_to_srgb(image_linear).astype(np.float32))
    except RoomlightError as exc:
        raise RoomlightError(f"{image_path}: the {name} estimator cannot run: {exc}; {need_depth}") from None
    return as_estimate(result, w, h, name=name)
