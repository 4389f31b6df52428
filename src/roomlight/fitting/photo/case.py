"""A photograph to fit, and the on-disk "photo case" folder (docs/file-formats.md, "Photo cases").

A photo case folder holds:

- ``image.exr`` (linear RGB, channels R, G, B), or ``image.png`` / ``image.jpg`` (8-bit sRGB);
- ``depth.exr`` (channel Z), ``depth.npy`` or ``depth.png`` (16-bit, millimetres): metric depth of
  every pixel, z-depth or radial distance as ``camera.json`` says;
- ``mask.png`` (or ``.npy`` / ``.exr``): the objects of interest (:mod:`roomlight.fitting.photo.masks`);
- ``normals.exr`` (channels X, Y, Z) or ``normals.npy``: optional per-pixel unit normals in the
  camera frame (x right, y up, z towards the viewer);
- ``camera.json``: ``{"format": "roomlight.photo-case", "version": 1, "width": W, "height": H,
  "intrinsics": {"fx", "fy", "cx", "cy"}`` (pixels, or ``"fov_deg"`` for a centred square-pixel
  camera) ``, "depth_kind": "z" | "radial"``, optionally ``"pitch_deg"``, ``"roll_deg"``}.

Other files (a ``truth/`` folder from :mod:`roomlight.fitting.photo.synthetic`, previews) are ignored.
:func:`load_photo` reads such a folder or single files given one by one (the command line), and
refuses what it cannot use with one line naming the file and the problem.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from roomlight.errors import InputFileError, RoomlightError
from roomlight.fitting.photo.camera import PhotoCamera
from roomlight.fitting.photo.masks import ObjectLabels, labels_from_array, read_mask_array
from roomlight.fitting.photo.unproject import DEPTH_KINDS

__all__ = ["CASE_FORMAT", "CASE_VERSION", "IMAGE_NAMES", "DEPTH_NAMES", "MASK_NAMES", "NORMAL_NAMES",
           "DEFAULT_DEPTH_KIND", "PhotoCase", "read_image", "read_photo_depth", "read_normals", "read_camera_json",
           "load_photo", "write_photo_case"]

CASE_FORMAT = "roomlight.photo-case"
CASE_VERSION = 1
IMAGE_NAMES = ("image.exr", "image.png", "image.jpg", "image.jpeg")
DEPTH_NAMES = ("depth.exr", "depth.npy", "depth.png")
MASK_NAMES = ("mask.png", "mask.npy", "mask.exr")
NORMAL_NAMES = ("normals.exr", "normals.npy")
#: Depth files are z-depth unless said otherwise: what depth sensors and monocular estimators give.
DEFAULT_DEPTH_KIND = "z"
IMAGE_EXTENSIONS = (".exr", ".png", ".jpg", ".jpeg")


@dataclass
class PhotoCase:
    """A photograph with what the fit needs to know about it.

    Attributes:
        image: (H, W, 3) float32 linear RGB.
        depth: (H, W) float32 metres (``depth_kind``: ``z`` or ``radial``).
        intrinsics: the camera, for an H x W image.
        objects: the object labels (H, W) and how they were read.
        normals: optional (H, W, 3) float32 camera-frame unit normals.
        pitch_deg, roll_deg: the camera's orientation relative to the room (level: 0, 0).
        files: the files read, by role (``image``, ``depth``, ``mask``, ``normals``, ``camera``).
        notes: remarks for the user (repairs, ignored objects, the estimator used).
    """

    image: np.ndarray
    depth: np.ndarray
    depth_kind: str
    intrinsics: PhotoCamera
    objects: ObjectLabels
    normals: np.ndarray | None = None
    pitch_deg: float = 0.0
    roll_deg: float = 0.0
    files: dict[str, str] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)

    @property
    def height(self) -> int:
        return self.image.shape[0]

    @property
    def width(self) -> int:
        return self.image.shape[1]

    def camera_json(self) -> dict:
        """The ``camera.json`` content describing this case."""
        return {"format": CASE_FORMAT, "version": CASE_VERSION, "width": self.width, "height": self.height,
                "intrinsics": self.intrinsics.intrinsics_dict(), "depth_kind": self.depth_kind,
                "pitch_deg": self.pitch_deg, "roll_deg": self.roll_deg}


# ---------------------------------------------------------------------------------------- readers
def read_image(path) -> tuple[np.ndarray, list[str]]:
    """(H, W, 3) float32 linear RGB of a photo file, and notes on repairs.

    8-bit PNG / JPEG are sRGB-encoded and decoded to linear with the sRGB transfer function;
    an EXR is linear already (R, G, B channels, or Y for grey).
    """
    p = Path(path)
    if not p.exists():
        raise InputFileError(p, "image file does not exist")
    if not p.is_file():
        raise InputFileError(p, "is not a regular file")
    ext = p.suffix.lower()
    if ext not in IMAGE_EXTENSIONS:
        raise InputFileError(p, f"unsupported image format {ext or '(none)'}; expected an 8-bit PNG/JPEG "
                                "(sRGB) or a linear EXR")
    notes: list[str] = []
    if ext == ".exr":
        from roomlight.core.io import read_exr

        ch = read_exr(p)
        if all(c in ch for c in "RGB"):
            img = np.stack([ch[c] for c in "RGB"], -1).astype(np.float32)
        elif "Y" in ch:
            img = np.repeat(ch["Y"][..., None], 3, -1).astype(np.float32)
        else:
            raise InputFileError(p, f"expected R, G, B (or Y) channels, found {', '.join(ch)}")
        bad = ~np.isfinite(img).all(-1)
        if bad.any():
            raise InputFileError(p, f"image has {int(bad.sum())} of {bad.size} pixels with NaN or infinite values")
        neg = (img < 0).any(-1)
        if neg.any():
            img = np.maximum(img, 0.0)
            notes.append(f"{p}: clamped {int(neg.sum())} pixel(s) with negative values to 0")
        return img, notes
    from PIL import Image

    from roomlight.core.color import srgb_to_linear

    try:
        with Image.open(p) as im:
            mode = im.mode
            if mode not in ("RGB", "RGBA", "L", "LA", "P", "CMYK"):
                raise InputFileError(p, f"expected an 8-bit RGB or grey image, got PIL mode {mode!r}",
                                     "save 16-bit or float photos as a linear EXR")
            rgb = np.asarray(im.convert("RGB"), dtype=np.float64) / 255.0
    except InputFileError:
        raise
    except Exception as exc:
        raise InputFileError(p, f"cannot read the image ({str(exc).splitlines()[0] if str(exc) else type(exc).__name__})") from None
    return srgb_to_linear(rgb).astype(np.float32), notes


def _check_size(path, what: str, shape, image_path, image_shape) -> None:
    if tuple(shape[:2]) != tuple(image_shape[:2]):
        raise InputFileError(path, f"{what} is {shape[1]}x{shape[0]} but the image {image_path} is "
                                   f"{image_shape[1]}x{image_shape[0]}", f"resample the {what} to the image's size")


def read_photo_depth(path) -> np.ndarray:
    """(H, W) float32 metres from ``.exr`` / ``.npy`` / 16-bit ``.png`` (mm), checked to be finite and > 0."""
    from roomlight.core.io import read_depth

    d = np.asarray(read_depth(path), dtype=np.float32)
    if d.ndim != 2:
        raise InputFileError(path, f"expected an (H, W) depth map, got shape {d.shape}")
    bad = ~np.isfinite(d)
    if bad.any():
        raise InputFileError(path, f"depth has {int(bad.sum())} of {d.size} pixels with NaN or infinite values",
                             "fill holes (windows, missing returns) with a finite distance in metres")
    nonpos = d <= 0
    if nonpos.any():
        raise InputFileError(path, f"depth has {int(nonpos.sum())} of {d.size} pixels with zero or negative "
                                   f"values (minimum {float(d.min()):.4g}); depth must be in metres, > 0",
                             "fill holes (0 often marks 'no measurement') with a valid distance")
    return d


def read_normals(path) -> np.ndarray:
    """(H, W, 3) float32 unit normals from ``.npy`` or ``.exr`` (channels X, Y, Z or R, G, B)."""
    p = Path(path)
    if not p.is_file():
        raise InputFileError(p, "normals file does not exist")
    ext = p.suffix.lower()
    if ext == ".npy":
        try:
            n = np.load(p, allow_pickle=False)
        except Exception as exc:
            raise InputFileError(p, f"cannot be read as a .npy array: {exc}") from None
    elif ext == ".exr":
        from roomlight.core.io import read_exr

        ch = read_exr(p)
        names = next((c for c in ("XYZ", "RGB") if all(x in ch for x in c)), None)
        if names is None:
            raise InputFileError(p, f"expected channels X, Y, Z (or R, G, B), found {', '.join(ch)}")
        n = np.stack([ch[x] for x in names], -1)
    else:
        raise InputFileError(p, f"unsupported normals format {ext or '(none)'}; expected .npy or .exr")
    n = np.asarray(n, dtype=np.float32)
    if n.ndim != 3 or n.shape[2] != 3:
        raise InputFileError(p, f"expected (H, W, 3) normals, got shape {n.shape}")
    length = np.linalg.norm(n, axis=-1)
    bad = ~np.isfinite(length) | (length < 1e-6)
    if bad.all():
        raise InputFileError(p, "every normal is zero or not finite")
    out = np.where(bad[..., None], 0.0, n / np.where(bad, 1.0, length)[..., None]).astype(np.float32)
    return out  # zero rows mark pixels without a normal: the mesh's own normal is used there


def read_camera_json(path) -> dict:
    """Validated ``camera.json`` of a photo case (see the module docstring)."""
    p = Path(path)
    if not p.is_file():
        raise InputFileError(p, "camera.json does not exist", "a photo case folder needs camera.json")
    try:
        data = json.loads(p.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise InputFileError(p, f"cannot be read as JSON ({exc})") from None
    if not isinstance(data, dict):
        raise InputFileError(p, "expected a JSON object")
    known = {"format", "version", "width", "height", "intrinsics", "fov_deg", "depth_kind", "pitch_deg", "roll_deg",
             "units", "notes"}
    unknown = sorted(set(data) - known)
    if unknown:
        raise InputFileError(p, f"unknown key(s) {', '.join(unknown)}; expected some of {', '.join(sorted(known))}")
    if data.get("format", CASE_FORMAT) != CASE_FORMAT:
        raise InputFileError(p, f"format is {data['format']!r}, expected {CASE_FORMAT!r}")
    if int(data.get("version", CASE_VERSION)) > CASE_VERSION:
        raise InputFileError(p, f"version {data['version']} is newer than this roomlight reads ({CASE_VERSION})")
    for key in ("width", "height"):
        if key in data and not (isinstance(data[key], int) and data[key] > 0):
            raise InputFileError(p, f"{key} must be a positive integer, got {data[key]!r}")
    if "intrinsics" in data:
        k = data["intrinsics"]
        if not isinstance(k, dict) or set(k) != {"fx", "fy", "cx", "cy"} or not all(
                isinstance(v, (int, float)) and not isinstance(v, bool) for v in k.values()):
            raise InputFileError(p, "intrinsics must be an object with numbers fx, fy, cx, cy (pixels)")
    if "fov_deg" in data and not (isinstance(data["fov_deg"], (int, float)) and 0 < data["fov_deg"] < 180):
        raise InputFileError(p, f"fov_deg must be a number in (0, 180), got {data['fov_deg']!r}")
    if data.get("depth_kind", DEFAULT_DEPTH_KIND) not in DEPTH_KINDS:
        raise InputFileError(p, f"depth_kind must be one of {', '.join(DEPTH_KINDS)}, got {data['depth_kind']!r}")
    for key in ("pitch_deg", "roll_deg"):
        if key in data and not (isinstance(data[key], (int, float)) and -90 <= data[key] <= 90):
            raise InputFileError(p, f"{key} must be a number of degrees in [-90, 90], got {data[key]!r}")
    if data.get("units", "metres") not in ("metres", "meters", "m"):
        raise InputFileError(p, f"units must be metres, got {data['units']!r}")
    return data


def _first(folder: Path, names) -> Path | None:
    return next((folder / n for n in names if (folder / n).is_file()), None)


def load_photo(image, *, depth=None, depth_kind: str | None = None, mask=None, normals=None, fov: float | None = None,
               intrinsics: str | PhotoCamera | None = None, pitch: float | None = None, roll: float | None = None,
               estimator=None, min_object_fraction: float = 0.0) -> PhotoCase:
    """Read a photograph and what describes it; arguments override a photo case folder's files.

    Args:
        image: an image file, or a photo case folder.
        depth: a depth file; without one (and no folder depth) ``estimator`` is run on the image.
        depth_kind: ``z`` or ``radial`` (default: the folder's camera.json, else ``z``).
        mask: the objects of interest (here or in the folder); without one the case has no objects and
            only the visible room constrains the light.
        normals: an optional per-pixel normals file.
        fov: horizontal field of view in degrees, or ``intrinsics`` ``"fx,fy,cx,cy"`` (pixels).
        pitch, roll: camera orientation in degrees (default: camera.json, else level).
        estimator: a monocular estimator (:mod:`roomlight.fitting.photo.estimator`): a name, a callable, or None.
        min_object_fraction: objects smaller than this fraction of the image are ignored.
    """
    from roomlight.fitting.photo.estimator import estimate_geometry

    src = Path(image)
    camera: dict = {}
    files: dict[str, str] = {}
    if src.is_dir():
        cam_path = src / "camera.json"
        camera = read_camera_json(cam_path)
        files["camera"] = str(cam_path)
        image_path = _first(src, IMAGE_NAMES)
        if image_path is None:
            raise InputFileError(src, f"photo case folder has no image ({' / '.join(IMAGE_NAMES)})")
        depth = depth if depth is not None else _first(src, DEPTH_NAMES)
        mask = mask if mask is not None else _first(src, MASK_NAMES)
        normals = normals if normals is not None else _first(src, NORMAL_NAMES)
    else:
        image_path = src
    img, notes = read_image(image_path)
    files["image"] = str(image_path)
    h, w = img.shape[:2]
    if camera and (camera.get("width", w), camera.get("height", h)) != (w, h):
        raise InputFileError(files["camera"], f"describes a {camera.get('width')}x{camera.get('height')} image but "
                                              f"{image_path} is {w}x{h}")

    # The intrinsics: the command line, then camera.json, then the estimator.
    K: PhotoCamera | None = None
    if intrinsics is not None and fov is not None:
        raise RoomlightError("pass either --fov or --intrinsics, not both")
    try:
        if isinstance(intrinsics, PhotoCamera):
            K = intrinsics
        elif intrinsics is not None:
            K = PhotoCamera.parse(intrinsics, w, h)
        elif fov is not None:
            K = PhotoCamera.from_fov(fov, w, h)
        elif "intrinsics" in camera:
            k = camera["intrinsics"]
            K = PhotoCamera(w, h, float(k["fx"]), float(k["fy"]), float(k["cx"]), float(k["cy"]))
        elif "fov_deg" in camera:
            K = PhotoCamera.from_fov(float(camera["fov_deg"]), w, h)
    except InputFileError:
        raise
    except RoomlightError as exc:
        where = files.get("camera") if intrinsics is None and fov is None else "the command line"
        raise RoomlightError(f"{where}: {exc}") from None

    kind = depth_kind or camera.get("depth_kind") or DEFAULT_DEPTH_KIND
    if kind not in DEPTH_KINDS:
        raise RoomlightError(f"depth kind {kind!r}: expected one of {', '.join(DEPTH_KINDS)}")
    normal_map = None
    if depth is not None:
        d = read_photo_depth(depth)
        _check_size(depth, "depth map", d.shape, image_path, img.shape)
        files["depth"] = str(depth)
    else:
        est = estimate_geometry(estimator, img, image_path)
        d, kind = est.depth, est.kind
        if est.depth.shape != (h, w):
            raise RoomlightError(f"{image_path}: the estimator returned a {d.shape[1]}x{d.shape[0]} depth map for a "
                                 f"{w}x{h} image")
        if K is None:
            K = est.intrinsics
        normal_map = est.normals
        files["depth"] = f"estimated ({est.name})"
        notes.append(f"{image_path}: depth{', intrinsics' if est.intrinsics is not None else ''}"
                     f"{' and normals' if est.normals is not None else ''} estimated by {est.name}")
    if K is None:
        raise RoomlightError(f"{image_path}: unknown camera intrinsics: pass --fov DEG (horizontal) or "
                             "--intrinsics fx,fy,cx,cy (pixels), or put them in the photo case's camera.json")
    if (K.width, K.height) != (w, h):
        K = K.scaled(w, h)

    if mask is None:
        # Without objects the photograph's own visible room still constrains the light: the frustum term
        # (the light seen through the photo's pixels) and the room's albedo bound.
        labels = ObjectLabels(np.zeros((h, w), np.int32), "none", [])
        notes.append("no mask: no objects of interest, so the light is fitted to the visible room alone "
                     "(pass --mask FILE to fit objects' materials too)")
    else:
        raw = read_mask_array(mask)
        _check_size(mask, "mask", raw.shape, image_path, img.shape)
        labels = labels_from_array(raw, min_object_fraction, where=str(mask))
        files["mask"] = str(mask)
        notes.extend(labels.notes)
    if normals is not None:
        normal_map = read_normals(normals)
        _check_size(normals, "normal map", normal_map.shape, image_path, img.shape)
        files["normals"] = str(normals)
    return PhotoCase(image=img, depth=d.astype(np.float32), depth_kind=kind, intrinsics=K, objects=labels,
                     normals=normal_map, pitch_deg=float(pitch if pitch is not None else camera.get("pitch_deg", 0.0)),
                     roll_deg=float(roll if roll is not None else camera.get("roll_deg", 0.0)), files=files,
                     notes=notes)


# ---------------------------------------------------------------------------------------- writer
def write_photo_case(folder, image: np.ndarray, depth: np.ndarray, labels: np.ndarray, intrinsics: PhotoCamera,
                     depth_kind: str = "radial", normals: np.ndarray | None = None, pitch_deg: float = 0.0,
                     roll_deg: float = 0.0) -> dict[str, Path]:
    """Write a photo case folder (module docstring): ``image.exr``, ``depth.exr``, ``mask.png``,
    optionally ``normals.exr``, ``preview.png`` (the image, sRGB) and ``camera.json``.

    Each file is written under a temporary name and renamed; ``camera.json`` comes last, so a
    folder with a camera.json is complete.

    Args:
        image: (H, W, 3) linear RGB; depth: (H, W) metres of ``depth_kind``; labels: (H, W)
            integer object labels (0 = background, at most 65535); normals: (H, W, 3) camera frame.
    """
    from PIL import Image

    from roomlight.core.color import linear_to_srgb
    from roomlight.core.io import save_png, write_exr

    out = Path(folder)
    out.mkdir(parents=True, exist_ok=True)
    img = np.asarray(image, dtype=np.float32)
    h, w = img.shape[:2]
    lab = np.asarray(labels)
    if depth.shape != (h, w) or lab.shape != (h, w):
        raise RoomlightError(f"photo case: image {w}x{h}, depth {depth.shape[::-1]} and labels {lab.shape[::-1]} "
                             "must have one size")
    if lab.min() < 0 or lab.max() > 65535:
        raise RoomlightError("photo case: labels must lie in [0, 65535]")
    if (intrinsics.width, intrinsics.height) != (w, h):
        raise RoomlightError(f"photo case: intrinsics are for {intrinsics.width}x{intrinsics.height}, the image is {w}x{h}")
    paths: dict[str, Path] = {}
    tag = f".tmp-{os.getpid()}"

    def put(name: str, write) -> None:
        final = out / name
        tmp = out / f".{name}{tag}{final.suffix}"
        write(tmp)
        os.replace(tmp, final)
        paths[name.split(".")[0]] = final

    put("image.exr", lambda p: write_exr(p, {c: img[..., i] for i, c in enumerate("RGB")}))
    put("depth.exr", lambda p: write_exr(p, {"Z": np.asarray(depth, np.float32)}))
    mode_dtype = np.uint8 if lab.max() <= 255 else np.uint16
    put("mask.png", lambda p: Image.fromarray(lab.astype(mode_dtype)).save(p, format="PNG"))
    if normals is not None:
        n = np.asarray(normals, np.float32)
        put("normals.exr", lambda p: write_exr(p, {c: n[..., i] for i, c in enumerate("XYZ")}))
    put("preview.png", lambda p: save_png(p, np.rint(linear_to_srgb(img) * 255).astype(np.uint8)))
    case = PhotoCase(img, np.asarray(depth, np.float32), depth_kind, intrinsics,
                     ObjectLabels(lab.astype(np.int32), "labels", []), pitch_deg=pitch_deg, roll_deg=roll_deg)
    put("camera.json", lambda p: p.write_text(json.dumps(case.camera_json(), indent=2)))
    return paths
