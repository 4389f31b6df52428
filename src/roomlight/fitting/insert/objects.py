"""Objects to insert: what they are (mesh file or built-in shape), what they are made of, and where they
stand in the photograph.

Placement (camera frame: x right, y up, looking along -z, metres of the depth map):

- ``at`` = (x, y) a pixel of the photograph on a visible surface: the surface point is the pixel's
  unprojected depth and its normal the depth's local plane there (a least-squares fit over a
  small window, turned towards the camera);
- ``at_xyz`` = a point in the camera frame, with the surface normal taken as "up" of the room
  (the camera's pitch and roll undone).

The object's own up axis (+y of its mesh) is turned onto the normal, it is turned by ``rotate``
degrees about that normal, scaled so its largest bounding-box side is ``scale`` metres, and moved
along the normal until its lowest point touches the surface: it rests on it.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from roomlight.errors import InputFileError, RoomlightError

__all__ = ["InsertSpec", "PlacedObject", "parse_material", "load_object_mesh", "place_object", "read_placements",
           "surface_at_pixel"]

#: Largest bounding-box side of an object when no --scale is given, as a fraction of its distance
#: from the camera (objects then look about equally large wherever they are put).
DEFAULT_SCALE_FRACTION = 0.15
#: Half-width in pixels (of the photograph) of the window the surface normal is fitted over.
NORMAL_WINDOW = 3


@dataclass
class InsertSpec:
    """One object to insert, as the user describes it.

    Attributes:
        object: a mesh file (OBJ, PLY, glTF/GLB) or a built-in shape name.
        at: (x, y) pixel of the photograph (0-based, x right, y down), or None.
        at_xyz: camera-frame point (metres), or None. Exactly one of ``at`` and ``at_xyz``.
        scale: largest bounding-box side in metres, or None (:data:`DEFAULT_SCALE_FRACTION` of
            the distance).
        rotate: degrees about the surface normal.
        material: ``mirror``, ``diffuse:R,G,B`` or ``principled:A,ROUGHNESS,METALLIC`` (A: one gray
            value or R,G,B); see :func:`parse_material`.
    """

    object: str = "sphere"
    at: tuple[float, float] | None = None
    at_xyz: tuple[float, float, float] | None = None
    scale: float | None = None
    rotate: float = 0.0
    material: str = "diffuse:0.8,0.8,0.8"

    def check(self, where: str = "placement") -> None:
        if (self.at is None) == (self.at_xyz is None):
            raise RoomlightError(f"{where}: give exactly one of --at X,Y (a pixel) and --at-xyz X,Y,Z (camera frame)")
        if self.scale is not None and not (math.isfinite(self.scale) and self.scale > 0):
            raise RoomlightError(f"{where}: --scale must be a positive number of metres, got {self.scale}")
        if not math.isfinite(self.rotate):
            raise RoomlightError(f"{where}: --rotate must be a number of degrees, got {self.rotate}")
        parse_material(self.material, where)


@dataclass
class PlacedObject:
    """An object in the camera frame, ready to render.

    Attributes:
        spec: what was asked.
        vertices: (V, 3) camera-frame positions, metres; faces: (F, 3).
        bsdf: its Mitsuba BSDF dict.
        point, normal: the surface point it rests on and the surface normal there (camera frame).
        scale: its largest bounding-box side, metres.
    """

    spec: InsertSpec
    vertices: np.ndarray
    faces: np.ndarray
    bsdf: dict
    point: np.ndarray
    normal: np.ndarray
    scale: float
    notes: list[str] = field(default_factory=list)

    def to_dict(self) -> dict:
        return {"object": self.spec.object, "at": list(self.spec.at) if self.spec.at is not None else None,
                "at_xyz": list(self.spec.at_xyz) if self.spec.at_xyz is not None else None,
                "point_camera": [round(float(v), 6) for v in self.point],
                "normal_camera": [round(float(v), 6) for v in self.normal], "scale_m": round(self.scale, 6),
                "rotate_deg": self.spec.rotate, "material": self.spec.material, "bsdf": self.bsdf,
                "vertices": int(len(self.vertices)), "triangles": int(len(self.faces))}


_NUM = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"


def parse_material(text: str, where: str = "--material") -> dict:
    """A material string as a Mitsuba BSDF dict.

    ``mirror`` (smooth silver), ``diffuse:R,G,B`` (Lambertian albedo in [0, 1]),
    ``principled:A,ROUGHNESS,METALLIC`` or ``principled:R,G,B,ROUGHNESS,METALLIC`` (Disney
    principled; every value in [0, 1]).
    """
    from roomlight.core.render.materials import material, principled_bsdf

    text = str(text).strip()
    if text == "mirror":
        return material("mirror")
    kind, _, rest = text.partition(":")
    values = rest.split(",") if rest else []
    if kind not in ("diffuse", "principled") or not values or not all(re.fullmatch(_NUM, v.strip()) for v in values):
        raise RoomlightError(f"{where}: cannot read the material {text!r}; use mirror, diffuse:R,G,B or "
                             "principled:ALBEDO,ROUGHNESS,METALLIC (e.g. diffuse:0.8,0.2,0.2)")
    nums = [float(v) for v in values]
    if any(not 0.0 <= v <= 1.0 for v in nums):
        raise RoomlightError(f"{where}: every value of {text!r} must lie in [0, 1]")
    if kind == "diffuse":
        if len(nums) == 1:
            nums = nums * 3
        if len(nums) != 3:
            raise RoomlightError(f"{where}: diffuse takes one gray value or R,G,B, got {len(nums)} values in {text!r}")
        return {"type": "diffuse", "reflectance": {"type": "rgb", "value": nums}}
    if len(nums) == 3:
        return principled_bsdf([nums[0]] * 3, nums[1], nums[2])
    if len(nums) == 5:
        return principled_bsdf(nums[:3], nums[3], nums[4])
    raise RoomlightError(f"{where}: principled takes ALBEDO,ROUGHNESS,METALLIC or R,G,B,ROUGHNESS,METALLIC, "
                         f"got {len(nums)} values in {text!r}")


def load_object_mesh(name: str) -> tuple[np.ndarray, np.ndarray]:
    """(vertices (V, 3), faces (F, 3)) of a built-in shape or a mesh file (OBJ, PLY, glTF/GLB)."""
    from roomlight.fitting.scene.shapes import BUILTIN_SHAPES, builtin_shape

    if name in BUILTIN_SHAPES:
        v, f = builtin_shape(name)
        return np.asarray(v, np.float64), np.asarray(f, np.int64)
    path = Path(name)
    if not path.is_file():
        raise InputFileError(path, "no such mesh file, and not a built-in shape",
                             f"built-in shapes: {', '.join(BUILTIN_SHAPES)}")
    suffix = path.suffix.lower()
    if suffix in (".obj", ".ply"):
        from roomlight.core.render.variant import mitsuba

        mi = mitsuba()
        try:
            m = mi.load_dict({"type": suffix[1:], "filename": str(path)})
        except Exception as exc:  # Mitsuba's parser errors: one line for the user
            raise InputFileError(path, f"cannot read the mesh: {str(exc).splitlines()[0]}") from None
        p = mi.traverse(m)
        v = np.array(p["vertex_positions"], dtype=np.float64).reshape(-1, 3)
        f = np.array(p["faces"], dtype=np.int64).reshape(-1, 3)
    elif suffix in (".gltf", ".glb"):
        v, f = _read_gltf(path)
    else:
        raise InputFileError(path, f"unsupported mesh format {suffix or '(none)'}", "use OBJ, PLY, glTF or GLB")
    if len(v) == 0 or len(f) == 0 or not np.isfinite(v).all():
        raise InputFileError(path, "the mesh has no triangles or non-finite vertices")
    return v, f


def _read_gltf(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """Every triangle mesh of a glTF/GLB scene, with its node transforms applied, as one mesh."""
    try:
        import trimesh
    except ImportError:
        raise InputFileError(path, "reading glTF needs trimesh", "pip install 'roomlight[export]'") from None
    try:
        scene = trimesh.load(str(path), force="scene")
        mesh = scene.to_geometry() if hasattr(scene, "to_geometry") else scene.dump(concatenate=True)
    except Exception as exc:  # trimesh raises many types for bad files
        raise InputFileError(path, f"cannot read the glTF file: {str(exc).splitlines()[0] if str(exc) else type(exc).__name__}") from None
    v = np.asarray(getattr(mesh, "vertices", np.zeros((0, 3))), np.float64)
    f = np.asarray(getattr(mesh, "faces", np.zeros((0, 3))), np.int64)
    # glTF is y up, right-handed, metres: the same axes as roomlight's object frame.
    return v, f


def surface_at_pixel(points: np.ndarray, x: float, y: float, where: str = "--at") -> tuple[np.ndarray, np.ndarray]:
    """(point (3,), unit normal (3,) facing the camera) of the surface a pixel sees.

    Args:
        points: (H, W, 3) camera-frame points of every pixel of the photograph (NaN where there is
            no depth, e.g. the sky).
        x, y: pixel coordinates (0-based; fractions are rounded to the nearest pixel centre).
    """
    h, w = points.shape[:2]
    if not (0 <= x < w and 0 <= y < h):
        raise RoomlightError(f"{where} {x:g},{y:g}: outside the {w}x{h} photograph")
    i, j = min(int(round(y)), h - 1), min(int(round(x)), w - 1)
    p = points[i, j]
    if not np.isfinite(p).all():
        raise RoomlightError(f"{where} {x:g},{y:g}: the pixel has no depth (sky, a window or an invalid "
                             "depth value); pick a pixel on a surface")
    r = NORMAL_WINDOW
    win = points[max(0, i - r):i + r + 1, max(0, j - r):j + r + 1].reshape(-1, 3)
    win = win[np.isfinite(win).all(1)]
    if len(win) < 3:
        raise RoomlightError(f"{where} {x:g},{y:g}: too few pixels with depth around it to find the surface's "
                             "orientation; pick a pixel inside a surface")
    # A plane through the window, refitted without the points far from it: a depth step (another
    # object's edge) is an outlier of the surface the pixel is on, a floor seen at a grazing angle is not.
    dist = float(np.linalg.norm(p))
    keep = np.ones(len(win), bool)
    for _ in range(3):
        centre = win[keep].mean(0)
        normal = np.linalg.svd(win[keep] - centre, full_matrices=False)[2][-1]
        resid = np.abs((win - centre) @ normal)
        new_keep = resid <= max(0.01 * dist, 2.0 * float(np.median(resid[keep])))
        if new_keep.sum() < 3 or (new_keep == keep).all():
            break
        keep = new_keep
    if np.dot(normal, p) > 0:  # towards the camera (at the origin)
        normal = -normal
    return p.astype(np.float64), normal / np.linalg.norm(normal)


def _rotation_onto(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(3, 3) rotation taking unit vector a onto unit vector b (the shortest one)."""
    v = np.cross(a, b)
    c = float(np.dot(a, b))
    if c < -1 + 1e-9:  # opposite: a half turn about any axis perpendicular to a
        axis = np.cross(a, [1.0, 0.0, 0.0])
        if np.linalg.norm(axis) < 1e-6:
            axis = np.cross(a, [0.0, 0.0, 1.0])
        axis /= np.linalg.norm(axis)
        return 2 * np.outer(axis, axis) - np.eye(3)
    vx = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
    return np.eye(3) + vx + vx @ vx / (1.0 + c)


def _axis_rotation(axis: np.ndarray, degrees: float) -> np.ndarray:
    a = axis / np.linalg.norm(axis)
    t = math.radians(degrees)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + math.sin(t) * k + (1 - math.cos(t)) * k @ k


def place_object(spec: InsertSpec, points: np.ndarray, up: np.ndarray, where: str = "placement") -> PlacedObject:
    """Put ``spec``'s object on the surface (module docstring).

    Args:
        points: (H, W, 3) camera-frame points of the photograph's pixels (NaN without depth).
        up: (3,) the room's up direction in the camera frame (for ``at_xyz``).
    """
    spec.check(where)
    verts, faces = load_object_mesh(spec.object)
    if spec.at is not None:
        point, normal = surface_at_pixel(points, spec.at[0], spec.at[1], f"{where}: --at")
    else:
        point = np.asarray(spec.at_xyz, np.float64)
        if not np.isfinite(point).all() or point[2] >= 0:
            raise RoomlightError(f"{where}: --at-xyz {spec.at_xyz} must be finite and in front of the camera (z < 0)")
        normal = np.asarray(up, np.float64) / np.linalg.norm(up)
    extent = verts.max(0) - verts.min(0)
    size = spec.scale if spec.scale is not None else DEFAULT_SCALE_FRACTION * float(np.linalg.norm(point))
    local = (verts - 0.5 * (verts.max(0) + verts.min(0))) * (size / float(extent.max()))
    rot = _axis_rotation(normal, spec.rotate) @ _rotation_onto(np.array([0.0, 1.0, 0.0]), normal)
    world = local @ rot.T
    # Rest on the surface: the lowest point along the normal touches it, lifted by a hair so the
    # contact does not z-fight with the depth mesh.
    lift = -float((world @ normal).min()) + 1e-3 * size
    world = world + point + lift * normal
    return PlacedObject(spec, world, faces, parse_material(spec.material, where), point, normal, size)


def read_placements(path) -> list[InsertSpec]:
    """A placements file: a YAML or JSON list of objects (or ``{"objects": [...]}``), each with the keys
    of :class:`InsertSpec` (``object``, ``at`` or ``at_xyz``, ``scale``, ``rotate``, ``material``)."""
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as exc:
        raise InputFileError(path, f"cannot read the placements file ({exc.strerror})") from None
    try:
        if path.suffix.lower() in (".yaml", ".yml"):
            import yaml

            data = yaml.safe_load(text)
        else:
            import json

            data = json.loads(text)
    except Exception as exc:  # json / yaml parse errors
        raise InputFileError(path, f"cannot parse the placements: {str(exc).splitlines()[0]}") from None
    if isinstance(data, dict):
        data = data.get("objects")
    if not isinstance(data, list) or not data:
        raise InputFileError(path, "expected a list of objects (or {objects: [...]})")
    specs = []
    known = {"object", "at", "at_xyz", "scale", "rotate", "material"}
    for k, entry in enumerate(data):
        where = f"{path}: object {k}"
        if not isinstance(entry, dict):
            raise InputFileError(path, f"object {k} is not a mapping")
        unknown = set(entry) - known
        if unknown:
            raise InputFileError(path, f"object {k}: unknown key(s) {', '.join(sorted(unknown))}",
                                 f"known: {', '.join(sorted(known))}")
        try:
            spec = InsertSpec(object=str(entry.get("object", "sphere")),
                              at=_vector(entry.get("at"), 2, "at"), at_xyz=_vector(entry.get("at_xyz"), 3, "at_xyz"),
                              scale=None if entry.get("scale") is None else float(entry["scale"]),
                              rotate=float(entry.get("rotate", 0.0)),
                              material=str(entry.get("material", InsertSpec.material)))
        except (TypeError, ValueError) as exc:
            raise InputFileError(path, f"object {k}: {exc}") from None
        spec.check(where)
        specs.append(spec)
    return specs


def _vector(value, n: int, name: str):
    if value is None:
        return None
    if isinstance(value, str):
        value = value.split(",")
    v = tuple(float(x) for x in value)
    if len(v) != n:
        raise ValueError(f"{name} needs {n} numbers, got {len(v)}")
    return v
