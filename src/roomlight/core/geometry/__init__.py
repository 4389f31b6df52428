"""Spherical geometry: the equirectangular convention, projections, padding and rotations."""

from roomlight.core.geometry.equirect import (
    check_equirect_shape,
    direction_to_uv,
    latitude_channels,
    pixel_directions,
    pixel_solid_angles,
    pixel_uv,
    sample_equirect,
    uv_to_direction,
)
from roomlight.core.geometry.analytic import box_distance, box_room_depth
from roomlight.core.geometry.padding import SphericalPad, spherical_pad
from roomlight.core.geometry.projection import (
    camera_basis,
    panorama_to_perspective,
    perspective_directions,
    perspective_to_panorama,
)
from roomlight.core.geometry.resample import resize_panorama
from roomlight.core.geometry.rotation import rotate_panorama, rotation_matrix

__all__ = [
    "box_distance", "box_room_depth", "resize_panorama",
    "check_equirect_shape", "direction_to_uv", "latitude_channels", "pixel_directions",
    "pixel_solid_angles", "pixel_uv", "sample_equirect", "uv_to_direction",
    "SphericalPad", "spherical_pad", "camera_basis", "panorama_to_perspective",
    "perspective_directions", "perspective_to_panorama", "rotate_panorama", "rotation_matrix",
]
