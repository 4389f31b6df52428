"""Sensors: Mitsuba perspective cameras from origin / look-at / fov, and equirectangular rays."""

from __future__ import annotations

import math

from roomlight.errors import RoomlightError
from roomlight.core.render.variant import mitsuba

__all__ = ["perspective_sensor", "pinhole_sensor", "cropped_sensor"]


def perspective_sensor(origin=(0.0, 0.0, 0.0), target=(0.0, 0.0, -1.0), up=(0.0, 1.0, 0.0),
                       fov_deg: float = 65.0, width: int = 256, height: int = 256,
                       pixel_filter: str = "box") -> dict:
    """Mitsuba ``perspective`` sensor dict (horizontal ``fov_deg``, ``hdrfilm`` RGB output).

    A box pixel filter is the default so that each pixel integrates only its own footprint
    (no blur across pixels), which makes renders comparable to direct resampling.
    """
    mi = mitsuba()
    if not 0.0 < fov_deg < 180.0:
        raise RoomlightError(f"camera: fov must be in (0, 180) degrees, got {fov_deg}")
    if width <= 0 or height <= 0:
        raise RoomlightError(f"camera: resolution must be positive, got {width}x{height}")
    if tuple(map(float, origin)) == tuple(map(float, target)):
        raise RoomlightError("camera: origin and look-at target coincide")
    return {
        "type": "perspective",
        "fov": float(fov_deg),
        "fov_axis": "x",
        "to_world": mi.ScalarTransform4f().look_at(origin=list(map(float, origin)),
                                                   target=list(map(float, target)),
                                                   up=list(map(float, up))),
        "film": {"type": "hdrfilm", "width": int(width), "height": int(height), "pixel_format": "rgb",
                 "rfilter": {"type": pixel_filter}},
        "sampler": {"type": "independent"},
    }


def pinhole_sensor(fx: float, cx: float, cy: float, width: int, height: int, origin=(0.0, 0.0, 0.0),
                   forward=(0.0, 0.0, -1.0), up=(0.0, 1.0, 0.0), pixel_filter: str = "box") -> dict:
    """Mitsuba ``perspective`` sensor of a photograph's pinhole camera given in pixels.

    Pixel coordinates have (0, 0) at the image's top-left corner and pixel centres at +0.5; the
    focal length ``fx`` (square pixels) and the principal point (``cx``, ``cy``) are in pixels of the
    ``width`` x ``height`` film. The camera sits at ``origin`` looking along ``forward`` with ``up``
    towards the image's top. Mitsuba's ``principal_point_offset_x`` / ``_y`` (fractions of the film's
    width / height) move the principal point from the film's centre to the left / upwards, so they
    are 0.5 - cx / W and 0.5 - cy / H.
    """
    if not fx > 0:
        raise RoomlightError(f"camera: the focal length must be positive, got {fx}")
    sensor = perspective_sensor(origin, [o + f for o, f in zip(map(float, origin), map(float, forward))], up,
                                math.degrees(2.0 * math.atan(width / (2.0 * fx))), width, height, pixel_filter)
    sensor["principal_point_offset_x"] = 0.5 - float(cx) / width
    sensor["principal_point_offset_y"] = 0.5 - float(cy) / height
    return sensor


def cropped_sensor(sensor: dict, x0: int, y0: int, width: int, height: int) -> dict:
    """A copy of a sensor dict whose film renders only the window [y0, y0+height) x [x0, x0+width).

    The pixels inside the window have the same distribution as in the full frame (same
    camera rays, same filter); ``mi.render`` then returns a (height, width, C) image.
    """
    film = dict(sensor["film"])
    fw, fh = int(film["width"]), int(film["height"])
    if not (0 <= x0 < x0 + width <= fw and 0 <= y0 < y0 + height <= fh):
        raise RoomlightError(f"camera: crop window x {x0}+{width}, y {y0}+{height} is outside the {fw}x{fh} film")
    film.update(crop_offset_x=int(x0), crop_offset_y=int(y0), crop_width=int(width), crop_height=int(height))
    return {**sensor, "film": film}
