"""File input/output: panoramas (EXR, Radiance HDR), depth maps, previews and meshes.

See ``docs/file-formats.md`` for the formats. Everything here works on numpy arrays; torch
tensors are accepted where noted and never required (``import roomlight.core.io`` does not import
torch).
"""

from __future__ import annotations

from roomlight.core.io.depth import read_depth, write_depth, write_depth_png
from roomlight.core.io.exr import read_exr, read_exr_with_header, write_exr
from roomlight.core.io.panorama import (
    EXPOSURE_FACTOR_KEY,
    METADATA_ATTRIBUTE,
    Panorama,
    calibrate_panorama,
    exposure_calibrate,
    exposure_uncalibrate,
    luminance,
    read_panorama,
    write_panorama,
)
from roomlight.core.io.ply import read_ply, write_ply
from roomlight.core.io.preview import (
    colorize_depth,
    inverse_reinhard_extended,
    reinhard_extended,
    save_png,
    save_radiance_preview,
    tonemap_gamma,
)
from roomlight.core.io.rgbe import read_hdr, read_hdr_with_header, write_hdr

__all__ = [
    # panoramas
    "Panorama", "read_panorama", "write_panorama", "METADATA_ATTRIBUTE",
    "luminance", "exposure_calibrate", "exposure_uncalibrate", "calibrate_panorama",
    "EXPOSURE_FACTOR_KEY",
    # formats
    "read_exr", "read_exr_with_header", "write_exr",
    "read_hdr", "read_hdr_with_header", "write_hdr",
    "read_depth", "write_depth", "write_depth_png",
    "read_ply", "write_ply",
    # previews
    "tonemap_gamma", "reinhard_extended", "inverse_reinhard_extended", "colorize_depth",
    "save_png", "save_radiance_preview",
]
