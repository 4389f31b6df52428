"""Scene descriptions for inverse rendering and the benchmark (JSON or YAML on disk).

A scene holds a camera per view, objects with known geometry / pose / material, the emitter
(a panorama with depth; the ground truth in a synthetic benchmark, optional for real data),
and per view the target image and object mask. Paths are relative to the scene file.
See ``docs/scene-format.md`` for the documented format and an example.

Everything is validated when the file is loaded: a missing, unknown or invalid field, or a file
that cannot be read, raises :class:`SceneError` naming the field (``objects[1].material.type``)
or the file; an unknown field also names the closest valid one (``fov_deg``: did you mean ``fov``?).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from roomlight.core.config import check_keys
from roomlight.errors import RoomlightError

__all__ = ["SceneError", "CameraSpec", "MaterialSpec", "ObjectSpec", "ViewSpec", "EmitterSpec", "SceneSpec",
           "save_scene", "parse_scene", "MATERIAL_TYPES"]

SCENE_VERSION = 1
MATERIAL_TYPES = ("diffuse", "matte", "mirror", "principled", "glossy", "white")
SCENE_EXTENSIONS = (".json", ".yaml", ".yml")

# The fields each part of a scene description may hold; anything else is refused as a likely typo.
_SCENE_KEYS = ("version", "objects", "views", "emitter", "metadata")
_CAMERA_KEYS = ("origin", "target", "up", "fov", "width", "height")
_OBJECT_KEYS = ("id", "shape", "mesh", "translate", "scale", "rotate", "material")
_MATERIAL_KEYS = ("type", "reflectance", "base_color", "alpha", "roughness", "metallic")
#: The parameters each material type reads (see MaterialSpec.bsdf).
_MATERIAL_PARAMS = {"diffuse": ("reflectance",), "matte": ("alpha",), "mirror": (),
                    "principled": ("base_color", "roughness", "metallic"), "glossy": (), "white": ()}
_VIEW_KEYS = ("camera", "objects", "image", "ldr", "mask")
_EMITTER_KEYS = ("panorama", "depth")


class SceneError(RoomlightError):
    """A scene description is missing a field, has an invalid value, or names an unreadable file."""


# ------------------------------------------------------------------------------------ helpers
def _keys(d, known, where: str) -> None:
    check_keys(d, known, where, error=SceneError)


def _get(d: dict, key: str, where: str, kind=None, default=...):
    if not isinstance(d, dict):
        raise SceneError(f"{where}: expected a mapping, got {type(d).__name__}")
    if key not in d:
        if default is ...:
            raise SceneError(f"{where}.{key}: missing (required)")
        return default
    value = d[key]
    if kind is not None and (not isinstance(value, kind) or (isinstance(value, bool) and kind is int)):
        names = kind.__name__ if isinstance(kind, type) else "/".join(k.__name__ for k in kind)
        raise SceneError(f"{where}.{key}: expected {names}, got {value!r}")
    return value


def _vec(value, where: str, n: int = 3) -> tuple[float, ...]:
    try:
        if not isinstance(value, (list, tuple)) or not all(_is_number(v) for v in value):
            raise ValueError
        out = tuple(float(v) for v in value)
        if len(out) != n or not all(math.isfinite(v) for v in out):
            raise ValueError
        return out
    except (TypeError, ValueError):
        raise SceneError(f"{where}: expected {n} finite numbers, got {value!r}") from None


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _positive(value, where: str) -> float:
    try:
        v = float(value) if _is_number(value) else float("nan")
    except OverflowError:  # an integer too large for a float
        v = float("inf")
    if not v > 0 or not math.isfinite(v):
        raise SceneError(f"{where}: expected a positive number, got {value!r}")
    return v


def _positive_int(value, where: str) -> int:
    _positive(value, where)
    if not isinstance(value, int):
        raise SceneError(f"{where}: expected a whole number of pixels, got {value!r}")
    return value


def _file(root: Path, value, where: str) -> Path:
    if not isinstance(value, str) or not value:
        raise SceneError(f"{where}: expected a file path, got {value!r}")
    p = (root / value).resolve() if not Path(value).is_absolute() else Path(value)
    if not p.is_file():
        raise SceneError(f"{where}: file {p} does not exist")
    return p


# ------------------------------------------------------------------------------------ specs
@dataclass
class CameraSpec:
    """A pinhole camera. ``fov`` is horizontal, in degrees; positions in metres."""

    origin: tuple[float, float, float] = (0.0, 0.0, 0.0)
    target: tuple[float, float, float] = (0.0, 0.0, -1.0)
    up: tuple[float, float, float] = (0.0, 1.0, 0.0)
    fov: float = 65.0
    width: int = 256
    height: int = 256

    @classmethod
    def parse(cls, d: dict, where: str) -> "CameraSpec":
        _keys(d, _CAMERA_KEYS, where)
        c = cls(origin=_vec(_get(d, "origin", where, default=[0, 0, 0]), f"{where}.origin"),
                target=_vec(_get(d, "target", where, default=[0, 0, -1]), f"{where}.target"),
                up=_vec(_get(d, "up", where, default=[0, 1, 0]), f"{where}.up"),
                fov=_positive(_get(d, "fov", where, default=65.0), f"{where}.fov"),
                width=_positive_int(_get(d, "width", where), f"{where}.width"),
                height=_positive_int(_get(d, "height", where), f"{where}.height"))
        if c.fov >= 180:
            raise SceneError(f"{where}.fov: must be below 180 degrees, got {c.fov}")
        if np.allclose(c.origin, c.target):
            raise SceneError(f"{where}: origin and target coincide")
        return c

    def to_dict(self) -> dict:
        return {"origin": list(self.origin), "target": list(self.target), "up": list(self.up),
                "fov": self.fov, "width": self.width, "height": self.height}

    def sensor(self, width: int | None = None, height: int | None = None) -> dict:
        """Mitsuba sensor dict (optionally at another resolution)."""
        from roomlight.core.render.camera import perspective_sensor

        return perspective_sensor(self.origin, self.target, self.up, self.fov, width or self.width,
                                  height or self.height)


@dataclass
class MaterialSpec:
    """A material: ``type`` in MATERIAL_TYPES plus its parameters.

    diffuse: reflectance (RGB, default 0.5 gray); matte: silver rough conductor, alpha (0.2);
    mirror: silver smooth conductor; principled: base_color, roughness, metallic;
    glossy: rough plastic; white: albedo-1 Lambertian.
    """

    type: str = "diffuse"
    params: dict = field(default_factory=dict)

    @classmethod
    def parse(cls, d, where: str) -> "MaterialSpec":
        if isinstance(d, str):
            d = {"type": d}
        _keys(d, _MATERIAL_KEYS, where)
        t = _get(d, "type", where, str)
        if t not in MATERIAL_TYPES:
            raise SceneError(f"{where}.type: expected one of {', '.join(MATERIAL_TYPES)}, got {t!r}")
        params = {k: v for k, v in d.items() if k != "type"}
        wrong = sorted(set(params) - set(_MATERIAL_PARAMS[t]))
        if wrong:  # another type's parameter would be dropped without a word: refuse it
            takes = ", ".join(_MATERIAL_PARAMS[t]) or "no parameters"
            raise SceneError(f"{where}.{wrong[0]}: a {t} material does not take it (it takes {takes})")
        for key in ("reflectance", "base_color"):
            if key in params:
                params[key] = list(_vec(params[key], f"{where}.{key}"))
        for key in ("alpha", "roughness", "metallic"):
            if key in params:
                v = float(params[key]) if _is_number(params[key]) else float("nan")
                if not 0 <= v <= 1:
                    raise SceneError(f"{where}.{key}: expected a value in [0, 1], got {params[key]!r}")
                params[key] = v
        return cls(t, params)

    def to_dict(self) -> dict:
        return {"type": self.type, **self.params}

    def bsdf(self) -> dict:
        """Mitsuba BSDF dict."""
        from roomlight.core.render.materials import material

        p = self.params
        if self.type == "diffuse":
            return {"type": "diffuse", "reflectance": {"type": "rgb", "value": p.get("reflectance", [0.5] * 3)}}
        if self.type == "matte":
            return {**material("matte"), "alpha": p.get("alpha", 0.2)}
        if self.type == "principled":
            return {"type": "principled", "base_color": {"type": "rgb", "value": p.get("base_color", [0.5] * 3)},
                    "roughness": p.get("roughness", 0.5), "metallic": p.get("metallic", 0.0)}
        return material(self.type)


@dataclass
class ObjectSpec:
    """An object: a built-in ``shape`` or a ``mesh`` file, placed by scale, rotation, translation.

    The transform applies scale, then rotation (``rotate``: axis x, y, z and angle in degrees),
    then translation, in metres in the capture frame.
    """

    id: str
    shape: str | None = None
    mesh: Path | None = None
    translate: tuple[float, float, float] = (0.0, 0.0, 0.0)
    scale: float = 1.0
    rotate: tuple[float, float, float, float] = (0.0, 1.0, 0.0, 0.0)
    material: MaterialSpec = field(default_factory=MaterialSpec)

    @classmethod
    def parse(cls, d: dict, where: str, root: Path) -> "ObjectSpec":
        from roomlight.fitting.scene.shapes import BUILTIN_SHAPES

        _keys(d, _OBJECT_KEYS, where)
        oid = _get(d, "id", where, str)
        shape = _get(d, "shape", where, str, default=None)
        mesh = _get(d, "mesh", where, str, default=None)
        if (shape is None) == (mesh is None):
            raise SceneError(f"{where}: give exactly one of 'shape' (built-in: {', '.join(BUILTIN_SHAPES)}) or 'mesh' (a .ply/.obj file)")
        if shape is not None and shape not in BUILTIN_SHAPES:
            raise SceneError(f"{where}.shape: unknown built-in shape {shape!r}; choose one of {', '.join(BUILTIN_SHAPES)}")
        mpath = None
        if mesh is not None:
            mpath = _file(root, mesh, f"{where}.mesh")
            if mpath.suffix.lower() not in (".ply", ".obj"):
                raise SceneError(f"{where}.mesh: {mpath.name}: expected a .ply or .obj file")
        rot = _get(d, "rotate", where, default=[0, 1, 0, 0])
        return cls(id=oid, shape=shape, mesh=mpath,
                   translate=_vec(_get(d, "translate", where, default=[0, 0, 0]), f"{where}.translate"),
                   scale=_positive(_get(d, "scale", where, default=1.0), f"{where}.scale"),
                   rotate=_vec(rot, f"{where}.rotate", 4),
                   material=MaterialSpec.parse(_get(d, "material", where, default={"type": "diffuse"}),
                                               f"{where}.material"))

    def to_dict(self, root: Path) -> dict:
        d = {"id": self.id}
        if self.shape:
            d["shape"] = self.shape
        else:
            d["mesh"] = _relative(self.mesh, root)
        d.update({"translate": list(self.translate), "scale": self.scale, "rotate": list(self.rotate),
                  "material": self.material.to_dict()})
        return d

    def matrix(self) -> np.ndarray:
        """(4, 4) object-to-world matrix."""
        from roomlight.core.geometry.rotation import rotation_matrix

        ax = self.rotate[:3]
        r = (rotation_matrix(ax, math.radians(self.rotate[3])).numpy() if np.linalg.norm(ax) > 0
             else np.eye(3))
        m = np.eye(4)
        m[:3, :3] = r * self.scale
        m[:3, 3] = self.translate
        return m


@dataclass
class ViewSpec:
    """One view: its camera, the objects it shows, and (when known) the target image and mask."""

    name: str
    camera: CameraSpec
    objects: list[str]
    image: Path | None = None   # linear HDR target (.exr)
    ldr: Path | None = None     # 8-bit image as a camera records it (.png)
    mask: Path | None = None    # object pixels (.png, nonzero = object)

    @classmethod
    def parse(cls, name: str, d: dict, where: str, root: Path, object_ids: set[str]) -> "ViewSpec":
        _keys(d, _VIEW_KEYS, where)
        objs = _get(d, "objects", where, list)
        for i, o in enumerate(objs):
            if not isinstance(o, str) or o not in object_ids:
                raise SceneError(f"{where}.objects[{i}]: no object with id {o!r} (known: {', '.join(sorted(object_ids))})")
        files = {}
        for key in ("image", "ldr", "mask"):
            v = _get(d, key, where, default=None)
            files[key] = _file(root, v, f"{where}.{key}") if v is not None else None
        return cls(name, CameraSpec.parse(_get(d, "camera", where, dict), f"{where}.camera"), list(objs), **files)

    def to_dict(self, root: Path) -> dict:
        d = {"camera": self.camera.to_dict(), "objects": self.objects}
        for key in ("image", "ldr", "mask"):
            if getattr(self, key) is not None:
                d[key] = _relative(getattr(self, key), root)
        return d


@dataclass
class EmitterSpec:
    """The emitter: a panorama (R,G,B[,Z] EXR, or .hdr) and optionally a separate depth file."""

    panorama: Path
    depth: Path | None = None

    @classmethod
    def parse(cls, d: dict, where: str, root: Path) -> "EmitterSpec":
        _keys(d, _EMITTER_KEYS, where)
        pano = _file(root, _get(d, "panorama", where, str), f"{where}.panorama")
        depth = _get(d, "depth", where, str, default=None)
        return cls(pano, _file(root, depth, f"{where}.depth") if depth else None)

    def to_dict(self, root: Path) -> dict:
        d = {"panorama": _relative(self.panorama, root)}
        if self.depth:
            d["depth"] = _relative(self.depth, root)
        return d

    def load(self):
        """The panorama as :class:`roomlight.core.io.Panorama` (errors name the file)."""
        from roomlight.core.io import read_panorama

        return read_panorama(self.panorama, depth_path=self.depth)


@dataclass
class SceneSpec:
    """A whole scene description; ``root`` is the directory relative paths refer to."""

    root: Path
    objects: dict[str, ObjectSpec]
    views: dict[str, ViewSpec]
    emitter: EmitterSpec | None = None
    metadata: dict = field(default_factory=dict)

    def view(self, name: str) -> ViewSpec:
        if name not in self.views:
            raise SceneError(f"scene has no view {name!r} (views: {', '.join(self.views)})")
        return self.views[name]

    def to_dict(self) -> dict:
        d = {"version": SCENE_VERSION,
             "objects": [o.to_dict(self.root) for o in self.objects.values()],
             "views": {k: v.to_dict(self.root) for k, v in self.views.items()}}
        if self.emitter:
            d["emitter"] = self.emitter.to_dict(self.root)
        if self.metadata:
            d["metadata"] = self.metadata
        return d


def _relative(path: Path, root: Path) -> str:
    try:
        return str(Path(path).resolve().relative_to(Path(root).resolve()))
    except ValueError:
        return str(path)


def parse_scene(data: dict, root: Path, where: str = "scene") -> SceneSpec:
    """Validate a scene mapping (as read from JSON/YAML) into a :class:`SceneSpec`."""
    root = Path(root)
    _keys(data, _SCENE_KEYS, where)
    version = _get(data, "version", where, int, default=SCENE_VERSION)
    if version != SCENE_VERSION:
        raise SceneError(f"{where}.version: this roomlight reads version {SCENE_VERSION}, got {version}")
    objs_raw = _get(data, "objects", where, list)
    objects: dict[str, ObjectSpec] = {}
    for i, od in enumerate(objs_raw):
        o = ObjectSpec.parse(od, f"{where}.objects[{i}]", root)
        if o.id in objects:
            raise SceneError(f"{where}.objects[{i}].id: duplicate id {o.id!r}")
        objects[o.id] = o
    views_raw = _get(data, "views", where, dict)
    if not views_raw:
        raise SceneError(f"{where}.views: at least one view is required")
    for name in views_raw:
        if not isinstance(name, str) or not name:
            raise SceneError(f"{where}.views: view names must be non-empty strings, got {name!r}")
    views = {name: ViewSpec.parse(name, vd, f"{where}.views.{name}", root, set(objects))
             for name, vd in views_raw.items()}
    em = _get(data, "emitter", where, dict, default=None)
    return SceneSpec(root, objects, views, EmitterSpec.parse(em, f"{where}.emitter", root) if em else None,
                     _get(data, "metadata", where, dict, default={}))


def read_scene(path) -> SceneSpec:
    """Read and validate a scene description (``.json``, ``.yaml`` or ``.yml``; or its folder).

    Only the description is checked here; :func:`roomlight.fitting.scene.build.load_scene` also reads
    every file it names.
    """
    p = Path(path)
    if p.is_dir():
        for name in ("scene.json", "scene.yaml", "scene.yml"):
            if (p / name).is_file():
                p = p / name
                break
    if not p.is_file():
        raise SceneError(f"{p}: no such scene file")
    if p.suffix.lower() not in SCENE_EXTENSIONS:
        raise SceneError(f"{p}: expected a scene description (.json, .yaml or .yml, see docs/scene-format.md), "
                         f"got a {p.suffix or 'file without extension'}")
    try:
        text = p.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise SceneError(f"{p}: not a text file; expected a scene description in JSON or YAML "
                         "(see docs/scene-format.md)") from None
    try:
        if p.suffix.lower() in (".yaml", ".yml"):
            import yaml

            data = yaml.safe_load(text)
        else:
            data = json.loads(text)
    except Exception as exc:
        raise SceneError(f"{p}: not valid {'YAML' if p.suffix.lower() in ('.yaml', '.yml') else 'JSON'}: {exc}") from None
    return parse_scene(data, p.parent, where=p.name)


def save_scene(scene: SceneSpec, path) -> Path:
    """Write a scene description as JSON (or YAML for a .yaml/.yml path)."""
    p = Path(path)
    d = scene.to_dict()
    if p.suffix.lower() in (".yaml", ".yml"):
        import yaml

        p.write_text(yaml.safe_dump(d, sort_keys=False))
    else:
        p.write_text(json.dumps(d, indent=2))
    return p
