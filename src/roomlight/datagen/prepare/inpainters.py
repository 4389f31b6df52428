"""Inpainters for the nadir view: OpenCV's (built in) and LaMa (when installed), or any callable.

An inpainter is a callable ``inpainter(image, mask) -> image``:

- ``image``: (h, w, 3) float32 display values (:class:`roomlight.datagen.prepare.tonemap.DisplayMap`),
  >= 0, about [0, 1]; the pixels under the mask are meaningless (black in a tripod capture);
- ``mask``: (h, w) bool, True where the image must be filled;
- returns (h, w, 3) float values; only the masked pixels are used.

:func:`resolve_inpainter` turns the names the command line takes into one: ``telea`` and ``ns``
(OpenCV's ``cv2.inpaint``, Telea's fast marching method or Navier-Stokes, from the package
``opencv-python-headless``: ``pip install roomlight[prepare]``), ``lama`` or ``lama:WEIGHTS``
(LaMa through the package ``simple-lama-inpainting`` and its TorchScript weights
``big-lama.pt``), or ``MODULE:FUNCTION`` for your own.
"""

from __future__ import annotations

import importlib
import os
from pathlib import Path

import numpy as np

from roomlight.errors import RoomlightError

__all__ = ["OpenCVInpainter", "LamaInpainter", "resolve_inpainter", "INPAINTER_NAMES"]

#: The built-in names of ``--inpainter``.
INPAINTER_NAMES = ("telea", "ns", "lama")


def _cv2():
    try:
        import cv2
    except ImportError as e:  # pragma: no cover - the test extra installs it
        raise RoomlightError(
            "the built-in inpainter needs OpenCV: pip install 'roomlight[prepare]' "
            "(opencv-python-headless), or pick --inpainter lama / MODULE:FUNCTION") from e
    return cv2


class OpenCVInpainter:
    """``cv2.inpaint`` on each colour channel in float32 (no 8-bit rounding of HDR display values).

    Args:
        method: ``telea`` (fast marching, Telea 2004) or ``ns`` (Navier-Stokes, Bertalmio 2001).
        radius: neighbourhood radius in view pixels.
    """

    def __init__(self, method: str = "telea", radius: float = 3.0):
        cv2 = _cv2()
        flags = {"telea": cv2.INPAINT_TELEA, "ns": cv2.INPAINT_NS}
        if method not in flags:
            raise RoomlightError(f"OpenCV inpainting method must be one of {sorted(flags)}, got {method!r}")
        self.method, self.radius, self._flag = method, float(radius), flags[method]
        self.name = f"opencv-{method}"

    def __call__(self, image: np.ndarray, mask: np.ndarray) -> np.ndarray:
        cv2 = _cv2()
        m = np.asarray(mask, bool).astype(np.uint8)
        img = np.ascontiguousarray(image, np.float32)
        # cv2.inpaint takes 3 channels only as 8-bit; one float channel at a time keeps the precision
        known = img[~np.asarray(mask, bool)]
        lo = known.min(axis=0) if known.size else np.zeros(img.shape[-1], np.float32)
        hi = known.max(axis=0) if known.size else np.ones(img.shape[-1], np.float32)
        channels = []
        for c in range(img.shape[-1]):
            ch = np.ascontiguousarray(img[..., c])
            if self.method == "telea":
                # Telea on float32 images overshoots wildly in OpenCV 5.0 (fills of -1.3 .. 1.8 for
                # data in 0 .. 0.5); on 16-bit integers it is sound, and 1/65535 of the range is
                # far below what an inpainting can claim to know.
                scale = 65535.0 / max(float(hi[c]), 1e-12)
                q = np.clip(np.rint(ch * scale), 0, 65535).astype(np.uint16)
                channels.append(cv2.inpaint(q, m, self.radius, self._flag).astype(np.float32) / scale)
            else:
                channels.append(cv2.inpaint(ch, m, self.radius, self._flag))
        # a fill never needs values outside the known pixels' range
        return np.clip(np.stack(channels, axis=-1), lo, hi)


class LamaInpainter:
    """LaMa (Suvorov et al. 2022) through ``simple-lama-inpainting``, on 8-bit display images.

    The weights are never downloaded: ``weights`` (or the ``LAMA_MODEL`` environment variable)
    must name the TorchScript file ``big-lama.pt``.
    """

    name = "lama"

    def __init__(self, weights: str | os.PathLike | None = None, device: str | None = None):
        try:
            from simple_lama_inpainting import SimpleLama
        except ImportError as e:
            raise RoomlightError(
                "--inpainter lama needs the package simple-lama-inpainting (pip install simple-lama-inpainting) "
                "and its weights big-lama.pt; or use the built-in --inpainter telea") from e
        path = weights or os.environ.get("LAMA_MODEL")
        if not path:
            raise RoomlightError(
                "--inpainter lama needs the LaMa weights: pass --inpainter lama:/path/to/big-lama.pt "
                "or set LAMA_MODEL=/path/to/big-lama.pt (they are not downloaded)")
        if not Path(path).is_file():
            raise RoomlightError(f"LaMa weights {path}: file does not exist (expected big-lama.pt, a TorchScript file)")
        import torch

        os.environ["LAMA_MODEL"] = str(path)  # SimpleLama reads the path from here and then skips its download
        dev = torch.device(device or ("cuda" if torch.cuda.is_available() else "cpu"))
        self._model = SimpleLama(device=dev)

    def __call__(self, image: np.ndarray, mask: np.ndarray) -> np.ndarray:
        from PIL import Image

        h, w = mask.shape
        rgb = (np.clip(image, 0.0, 1.0) * 255.0 + 0.5).astype(np.uint8)
        hole = np.asarray(mask, bool).astype(np.uint8) * 255
        out = self._model(Image.fromarray(rgb), Image.fromarray(hole))
        # the model pads to a multiple of 8; keep the original frame
        return np.asarray(out, np.float32)[:h, :w, :3] / 255.0


def resolve_inpainter(spec):
    """An inpainter from a name (see the module docstring) or a callable (returned as is)."""
    if callable(spec):
        return spec
    text = str(spec).strip()
    name, _, arg = text.partition(":")
    if name in ("telea", "ns"):
        return OpenCVInpainter(name, float(arg) if arg else 3.0)
    if name == "lama":
        return LamaInpainter(arg or None)
    if arg:
        return load_callable(text, "inpainter")
    raise RoomlightError(f"unknown inpainter {text!r}: use telea, ns, lama[:WEIGHTS] or MODULE:FUNCTION")


def load_callable(text: str, what: str):
    """``MODULE:NAME`` -> the object (a callable, or a class/factory that the caller instantiates)."""
    module, _, attr = text.partition(":")
    try:
        obj = importlib.import_module(module)
    except ImportError as e:
        raise RoomlightError(f"{what} {text!r}: cannot import module {module!r} ({e})") from e
    for part in attr.split("."):
        if not hasattr(obj, part):
            raise RoomlightError(f"{what} {text!r}: module {module!r} has no attribute {attr!r}")
        obj = getattr(obj, part)
    if not callable(obj):
        raise RoomlightError(f"{what} {text!r} is not callable")
    return obj
