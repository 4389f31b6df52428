"""What each method of the crop benchmark makes of one input crop: a panorama around the camera.

Every prediction is an (H, 2H, 3) linear panorama in roomlight's axes with the crop's camera looking at
+z (:data:`~roomlight.evaluation.crops.protocol.CROP_FORWARD`), the direction the truth's crop was cut
in. Its absolute level does not matter: the protocol normalises each panorama on its own.

The crop is an 8-bit image of the panorama tone-mapped with gamma 2.4; methods read it back to linear
as crop ** 2.4 (the protocol's curve, up to its unknown scale).
"""

from __future__ import annotations

import math

import numpy as np

from roomlight.errors import RoomlightError
from roomlight.evaluation.crops.protocol import CROP_SIZE, crop_camera_fov_x
from roomlight.fitting.methods import ESTIMATE_ROWS

__all__ = ["CROP_GAMMA", "crop_to_linear", "predict"]

#: The crop's display curve (the protocol's tone mapping).
CROP_GAMMA = 2.4


def crop_to_linear(crop: np.ndarray) -> np.ndarray:
    """(h, w, 3) display values in [0, 1] -> linear (up to the tone mapping's scale)."""
    return np.power(np.clip(np.asarray(crop, np.float64), 0.0, 1.0), CROP_GAMMA).astype(np.float32)


def _turn_to_plus_z(pano: np.ndarray) -> np.ndarray:
    """A panorama whose camera looked along -z (roomlight's photo frame), turned half a turn about the
    vertical so that it looks along +z: u -> u + 1/2."""
    return np.roll(pano, pano.shape[1] // 2, axis=1)


def _constant(crop_lin: np.ndarray, height: int = 64) -> np.ndarray:
    return np.broadcast_to(crop_lin.reshape(-1, 3).mean(0), (height, 2 * height, 3)).astype(np.float32).copy()


def _mirrored(crop_lin: np.ndarray, height: int = 128) -> np.ndarray:
    """The crop around the whole sphere: stretched over the front half (its left and right edges at 90°
    to either side, its top and bottom edges at the poles) and mirrored onto the back half (each edge
    continues into its own mirror image, the two halves meeting behind the camera)."""
    from roomlight.core.geometry.equirect import pixel_directions

    h, w = CROP_SIZE
    d = pixel_directions(height, 2 * height).numpy().astype(np.float64)
    # 0 at +z, the crop's centre; positive towards the crop's right, which is -x (right = forward x up)
    az = np.arctan2(-d[..., 0], d[..., 2])
    el = np.arcsin(np.clip(d[..., 1], -1.0, 1.0))
    a = az / (math.pi / 2)                                    # -2 .. 2, the crop spans -1 .. 1
    x_ndc = np.where(a > 1, 2 - a, np.where(a < -1, -2 - a, a))
    y_ndc = el / (math.pi / 2)
    x = (x_ndc + 1) / 2 * w - 0.5
    y = (1 - y_ndc) / 2 * h - 0.5
    xi = np.clip(np.rint(x).astype(int), 0, w - 1)
    yi = np.clip(np.rint(y).astype(int), 0, h - 1)
    return crop_lin[yi, xi].astype(np.float32)


def predict(method: str, crop: np.ndarray, model=None) -> np.ndarray:
    """The panorama ``method`` makes of ``crop`` ((192, 256, 3) display values in [0, 1])."""
    crop_lin = crop_to_linear(crop)
    if method == "constant-colour":
        return _constant(crop_lin)
    if method == "mirrored-crop":
        return _mirrored(crop_lin)
    if model is None:
        raise RoomlightError(f"crop method {method!r} needs a prior (--model)")
    import torch

    if method == "prior-mean":
        with torch.no_grad():
            rad, _ = model.decode(torch.zeros(1, model.config.latent_dim, device=next(model.parameters()).device))
        return rad[0].permute(1, 2, 0).cpu().numpy().astype(np.float32)
    if method in ESTIMATE_ROWS:
        from roomlight.fitting.photo.camera import PhotoCamera
        from roomlight.fitting.photo.estimate import estimate_light, estimate_row_settings

        camera = PhotoCamera.from_fov(crop_camera_fov_x(), CROP_SIZE[1], CROP_SIZE[0])
        est = estimate_light(crop_lin, camera, model, **estimate_row_settings(method))
        return _turn_to_plus_z(np.asarray(est.light.radiance, np.float32))
    raise RoomlightError(f"unknown crop method {method!r}")
