"""The photo case folder, as written by ``roomlight bench make-photos`` and read by its runner.

A photo case is what a method sees (the photo-case format of ``roomlight fit-photo``)::

    image.exr      linear RGB radiance, float32 (R, G, B), at the camera's exposure
    depth.exr      per-pixel depth for the methods, float32 channel Z, metres (planar z-depth)
    mask.png       8-bit integer labels: 0 background, 1..K the inserted objects
    camera.json    {"format": "roomlight.photo-case", "version": 1, "width", "height",
                    "intrinsics": {"fx", "fy", "cx", "cy"}, "depth_kind": "z", "pitch_deg",
                    "roll_deg", "units": "m"}

plus the ground truth, which no method reads::

    truth/photo.json           the record: room, camera, objects, probes, exposure, settings (written last)
    truth/camera.json          the camera's pose: intrinsics and ``camera_to_world`` (4 x 4, row-major)
    truth/materials.json       the objects' true materials and geometry, by label
    truth/probes.json          probe centres (world and camera frames), radii, labels, materials, the
                               probe window (x0, y0, w, h) and the truth's noise floor
    truth/depth.exr            the exact z-depth (depth.exr may be degraded)
    truth/probe_mask.png       probe labels: 1..P where a pixel is wholly covered by probe p
    truth/probes_<m>.exr/.png  the probe window of the photo re-rendered with the probes in material m
    truth/photo.png            the photo as an 8-bit recording (a preview)
    truth/oracle.exr           the room's light captured at the oracle centre: R, G, B + Z (radial, m)

Pixel coordinates have (0, 0) at the image's top-left corner (a centred principal point is
(W / 2, H / 2)). The camera frame is x right, y up, looking along -z; ``pitch_deg`` and
``roll_deg`` are the camera's tilt relative to the room (the room's yaw is not given: a method
cannot know it), and ``truth/camera.json`` holds the full pose (see
:mod:`roomlight.fitting.photo.camera`). Every file is written to a temporary name and renamed.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

from roomlight.errors import RoomlightError
from roomlight.fitting.photo.camera import PhotoCamera

__all__ = ["IMAGE", "DEPTH", "MASK", "CAMERA", "TRUTH", "RECORD", "MATERIALS", "PROBES", "TRUE_DEPTH",
           "PROBE_MASK", "ORACLE", "PREVIEW", "TRUE_CAMERA", "CASE_FORMAT", "CASE_VERSION", "probe_image_name", "write_json", "write_rgb_exr", "read_rgb_exr",
           "write_depth_exr", "read_depth_exr", "write_png", "read_labels", "camera_json", "read_camera",
           "read_json", "PhotoCaseError"]

IMAGE = "image.exr"
DEPTH = "depth.exr"
MASK = "mask.png"
CAMERA = "camera.json"
TRUTH = "truth"
RECORD = f"{TRUTH}/photo.json"
MATERIALS = f"{TRUTH}/materials.json"
PROBES = f"{TRUTH}/probes.json"
TRUE_DEPTH = f"{TRUTH}/depth.exr"
PROBE_MASK = f"{TRUTH}/probe_mask.png"
ORACLE = f"{TRUTH}/oracle.exr"
PREVIEW = f"{TRUTH}/photo.png"
TRUE_CAMERA = f"{TRUTH}/camera.json"
#: ``camera.json``'s format tag and version (the photo-case format of ``roomlight fit-photo``).
CASE_FORMAT = "roomlight.photo-case"
CASE_VERSION = 1


class PhotoCaseError(RoomlightError):
    """A photo case folder is missing a file or holds one that is not what the format says."""


def probe_image_name(material: str, ext: str = "exr") -> str:
    """``truth/probes_<material>.<ext>``."""
    return f"{TRUTH}/probes_{material}.{ext}"


def _tmp(path: Path) -> Path:
    return path.with_name(f".{path.stem}.{os.getpid()}.partial{path.suffix}")


def write_json(path, data) -> None:
    path = Path(path)
    tmp = _tmp(path)
    tmp.write_text(json.dumps(data, indent=2))
    os.replace(tmp, path)


def read_json(path) -> dict:
    p = Path(path)
    if not p.is_file():
        raise PhotoCaseError(f"{p}: no such file")
    try:
        return json.loads(p.read_text())
    except ValueError as exc:
        raise PhotoCaseError(f"{p}: not valid JSON ({exc})") from None


def write_rgb_exr(path, rgb: np.ndarray, metadata: dict | None = None) -> None:
    """(H, W, 3) linear RGB as float32 R, G, B."""
    from roomlight.core.io import write_exr

    path = Path(path)
    a = np.asarray(rgb, np.float32)
    tmp = _tmp(path)
    attrs = {"roomlight": json.dumps(metadata)} if metadata else None
    write_exr(tmp, {"R": a[..., 0], "G": a[..., 1], "B": a[..., 2]}, half=False, attributes=attrs)
    os.replace(tmp, path)


def read_rgb_exr(path) -> np.ndarray:
    """(H, W, 3) float32 from an EXR with R, G, B channels."""
    from roomlight.core.io import read_exr

    p = Path(path)
    if not p.is_file():
        raise PhotoCaseError(f"{p}: no such file")
    ch = read_exr(p)
    if not all(c in ch for c in "RGB"):
        raise PhotoCaseError(f"{p}: expected channels R, G, B, found {', '.join(sorted(ch))}")
    return np.stack([ch[c] for c in "RGB"], -1).astype(np.float32)


def write_depth_exr(path, depth: np.ndarray) -> None:
    """(H, W) metres as float32 channel Z."""
    from roomlight.core.io import write_exr

    path = Path(path)
    tmp = _tmp(path)
    write_exr(tmp, {"Z": np.asarray(depth, np.float32)}, half=False)
    os.replace(tmp, path)


def read_depth_exr(path) -> np.ndarray:
    from roomlight.core.io import read_exr

    p = Path(path)
    if not p.is_file():
        raise PhotoCaseError(f"{p}: no such file")
    ch = read_exr(p)
    if "Z" not in ch:
        raise PhotoCaseError(f"{p}: expected a depth channel Z, found {', '.join(sorted(ch))}")
    return ch["Z"].astype(np.float32)


def write_png(path, image: np.ndarray) -> None:
    """A uint8 (H, W) or (H, W, 3) PNG, written atomically."""
    from roomlight.core.io import save_png

    path = Path(path)
    tmp = _tmp(path)
    save_png(tmp, np.asarray(image, np.uint8))
    os.replace(tmp, path)


def read_labels(path) -> np.ndarray:
    """(H, W) int32 labels of an 8- or 16-bit single-channel PNG."""
    from PIL import Image

    p = Path(path)
    if not p.is_file():
        raise PhotoCaseError(f"{p}: no such file")
    with Image.open(p) as im:
        if im.mode not in ("L", "I;16", "I"):
            raise PhotoCaseError(f"{p}: expected a single-channel integer label PNG, got mode {im.mode}")
        return np.asarray(im, dtype=np.int32)


def camera_json(camera: PhotoCamera) -> dict:
    """The ``camera.json`` mapping of a case: what a method knows of the camera (z-depth, metres)."""
    _, pitch, roll = camera.orientation_deg()
    return {"format": CASE_FORMAT, "version": CASE_VERSION, "width": camera.width, "height": camera.height,
            "intrinsics": camera.intrinsics_dict(),
            "depth_kind": "z", "pitch_deg": pitch, "roll_deg": roll, "units": "m"}


def read_camera(case_dir) -> PhotoCamera:
    """The full camera (pose included) of a case, from ``truth/camera.json``."""
    path = Path(case_dir) / TRUE_CAMERA
    return PhotoCamera.from_dict(read_json(path), str(path))
