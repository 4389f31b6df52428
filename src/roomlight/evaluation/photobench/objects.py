"""The objects inserted into a photographed room, their materials, and the probe spheres.

An :class:`InsertedObject` is a closed mesh resting on a horizontal surface: a box (``box``,
three side lengths) or one of the built-in shapes of :mod:`roomlight.fitting.scene.shapes` (bounding
radius scaled to ``size[0]``), turned about the vertical by ``yaw`` and moved by ``translate``
(metres, world frame, y up). Its material is Mitsuba's ``principled`` BSDF with a uniform
``base_color`` (linear RGB albedo), ``roughness`` and ``metallic`` -- the parameters a photo fit
recovers per object; the same dict as ``{"type": "principled", ...}`` in a scene description.

A :class:`ProbeSphere` is an analytic sphere rendered with one of the synthetic benchmark's
probe materials (:data:`PROBE_MATERIALS`: gray diffuse, silver matte, silver mirror;
:mod:`roomlight.core.render.materials`).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from roomlight.errors import RoomlightError
from roomlight.core.render import mesh as render_mesh
from roomlight.core.render.materials import principled_bsdf

__all__ = ["PROBE_MATERIALS", "OBJECT_SHAPES", "PrincipledMaterial", "InsertedObject", "ProbeSphere", "box_mesh",
           "draw_material", "transform_points"]

#: The synthetic benchmark's probe materials (render.materials names).
PROBE_MATERIALS = ("diffuse", "matte", "mirror")
#: Shapes an inserted object can take: a box, or a built-in mesh.
OBJECT_SHAPES = ("box", "sphere", "cup", "blob", "torus", "knot", "spiky")


def box_mesh() -> tuple[np.ndarray, np.ndarray]:
    """The unit cube [-0.5, 0.5]^3: (vertices (8, 3) float64, faces (12, 3) int64), outward-facing."""
    v = np.array([[x, y, z] for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)], np.float64)
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    f = []
    for a, b, c, d in quads:
        f += [(a, b, c), (a, c, d)]
    f = np.asarray(f, np.int64)
    # orient outwards: the face normal must point away from the centre
    n = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    flip = (n * v[f].mean(1)).sum(1) < 0
    f[flip] = f[flip][:, [0, 2, 1]]
    return v, f


def transform_points(matrix: np.ndarray, points) -> np.ndarray:
    """Apply a (4, 4) transform to points (N, 3)."""
    m = np.asarray(matrix, np.float64)
    p = np.asarray(points, np.float64).reshape(-1, 3)
    return p @ m[:3, :3].T + m[:3, 3]


@dataclass(frozen=True)
class PrincipledMaterial:
    """A uniform principled material: linear RGB ``albedo`` (base colour) in [0, 1], ``roughness``
    and ``metallic`` in [0, 1] (Mitsuba ``principled`` parameters)."""

    albedo: tuple[float, float, float]
    roughness: float
    metallic: float

    def bsdf(self) -> dict:
        """Mitsuba BSDF dict."""
        return principled_bsdf(self.albedo, self.roughness, self.metallic)

    def to_dict(self) -> dict:
        return {"albedo": [float(c) for c in self.albedo], "roughness": float(self.roughness),
                "metallic": float(self.metallic)}

    @classmethod
    def from_dict(cls, d: dict) -> PrincipledMaterial:
        return cls(tuple(float(c) for c in d["albedo"]), float(d["roughness"]), float(d["metallic"]))


#: Reflectance at normal incidence (F0, linear RGB) of pure metals: a metal's base colour in a principled
#: BSDF. Every one reflects at least about half the light; a "metal" darker than that is optically a
#: glossy surface of that reflectance, which no real metal is.
REAL_METALS = {
    "silver": (0.95, 0.93, 0.88), "aluminium": (0.91, 0.92, 0.92), "gold": (1.00, 0.71, 0.29),
    "copper": (0.95, 0.64, 0.54), "iron": (0.56, 0.57, 0.58), "chromium": (0.55, 0.56, 0.55),
    "titanium": (0.54, 0.50, 0.45), "nickel": (0.66, 0.61, 0.53), "platinum": (0.67, 0.64, 0.59),
    "zinc": (0.66, 0.82, 0.85),
}

#: How a metal's base colour is drawn (:func:`draw_material`).
METAL_COLOURS = ("as-drawn", "real")


def draw_material(rng: np.random.Generator, metal_fraction: float = 0.3,
                  roughness_range=(0.15, 0.8), palette: str = "hsv", metal_colours: str = "as-drawn") -> PrincipledMaterial:
    """A random material, roughness uniform in ``roughness_range``, metallic 1 with probability
    ``metal_fraction`` and 0 otherwise (real surfaces are rarely in between).

    ``palette``: ``hsv`` (the original suite's): hue uniform, saturation 0-0.8, value 0.3-0.95 in
    sRGB-encoded HSV (linearised); ``wide`` (the wide suite's, the whole range of real surfaces): white
    (0.85-0.9), black (0.03-0.05), a saturated colour, or a grey log-uniform in 0.03-0.9, a quarter each.
    ``metal_colours``: ``as-drawn`` (both suites'): a metal keeps the base colour drawn from the palette,
    however dark; ``real``: a metal's base colour is a real metal's F0 (:data:`REAL_METALS`, one drawn
    uniformly). The draws before a metal's are the same either way.
    """
    from roomlight.datagen.synth.color import hsv_albedo

    if palette == "hsv":
        albedo = hsv_albedo(float(rng.uniform()), float(rng.uniform(0.0, 0.8)), float(rng.uniform(0.3, 0.95)))
    elif palette == "wide":
        kind = int(rng.integers(4))
        if kind == 0:
            albedo = (float(rng.uniform(0.85, 0.9)),) * 3
        elif kind == 1:
            albedo = (float(rng.uniform(0.03, 0.05)),) * 3
        elif kind == 2:
            albedo = hsv_albedo(float(rng.uniform()), float(rng.uniform(0.85, 1.0)), float(rng.uniform(0.6, 1.0)))
        else:
            albedo = (float(math.exp(rng.uniform(math.log(0.03), math.log(0.9)))),) * 3
        albedo = tuple(float(np.clip(c, 0.03, 0.9)) for c in albedo)
    else:
        raise ValueError(f"draw_material: unknown palette {palette!r}")
    roughness = float(rng.uniform(*roughness_range))
    metallic = 1.0 if rng.uniform() < metal_fraction else 0.0
    if metal_colours not in METAL_COLOURS:
        raise ValueError(f"draw_material: unknown metal_colours {metal_colours!r}")
    if metallic and metal_colours == "real":
        names = sorted(REAL_METALS)
        albedo = REAL_METALS[names[int(rng.integers(len(names)))]]
    return PrincipledMaterial(tuple(float(c) for c in albedo), roughness, metallic)


def _rot_y(deg: float) -> np.ndarray:
    a = math.radians(deg)
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


@dataclass(frozen=True)
class InsertedObject:
    """One inserted object (see the module docstring).

    Attributes:
        id: name (``obj1``, ...); label: its value in ``mask.png`` (1, 2, ...).
        shape: one of :data:`OBJECT_SHAPES`.
        size: box side lengths (x, y, z) in metres, or (bounding radius,) for a built-in shape.
        yaw: turn about +y, degrees; translate: (3,) metres, world frame.
        material: its principled material.
    """

    id: str
    label: int
    shape: str
    size: tuple
    yaw: float
    translate: tuple[float, float, float]
    material: PrincipledMaterial

    def __post_init__(self):
        if self.shape not in OBJECT_SHAPES:
            raise RoomlightError(f"object {self.id}: unknown shape {self.shape!r}; choose one of "
                                 f"{', '.join(OBJECT_SHAPES)}")
        if len(self.size) != (3 if self.shape == "box" else 1) or min(self.size) <= 0:
            raise RoomlightError(f"object {self.id}: size {self.size} does not fit shape {self.shape}")

    def local_geometry(self) -> tuple[np.ndarray, np.ndarray]:
        """(vertices (N, 3), faces (F, 3)) scaled and turned, before the translation."""
        if self.shape == "box":
            v, f = box_mesh()
            v = v * np.asarray(self.size, np.float64)
        else:
            from roomlight.fitting.scene.shapes import builtin_shape

            v, f = builtin_shape(self.shape)
            v, f = v.astype(np.float64) * float(self.size[0]), f.astype(np.int64)
        return v @ _rot_y(self.yaw).T, f

    def matrix(self) -> np.ndarray:
        """(4, 4) rigid part of the placement (turn, then translation)."""
        m = np.eye(4)
        m[:3, :3] = _rot_y(self.yaw)
        m[:3, 3] = self.translate
        return m

    def geometry(self, world_to_frame: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """World (or ``world_to_frame``) vertices (N, 3) float64 and faces (F, 3) int64."""
        v, f = self.local_geometry()
        v = v + np.asarray(self.translate, np.float64)
        return (v if world_to_frame is None else transform_points(world_to_frame, v)), f

    def mitsuba_mesh(self, world_to_frame: np.ndarray | None = None):
        """A ``mi.Mesh`` with its principled BSDF."""
        v, f = self.geometry(world_to_frame)
        return render_mesh.mitsuba_mesh(self.id, v, f, self.material.bsdf())

    def to_dict(self) -> dict:
        d = asdict(self)
        d["size"] = [float(s) for s in self.size]
        d["translate"] = [float(t) for t in self.translate]
        d["material"] = self.material.to_dict()
        d["bsdf"] = self.material.bsdf()
        return d

    @classmethod
    def from_dict(cls, d: dict) -> InsertedObject:
        return cls(str(d["id"]), int(d["label"]), str(d["shape"]), tuple(float(s) for s in d["size"]),
                   float(d["yaw"]), tuple(float(t) for t in d["translate"]), PrincipledMaterial.from_dict(d["material"]))


@dataclass(frozen=True)
class ProbeSphere:
    """A probe: centre (3,) metres (world frame) and radius (metres)."""

    id: str
    label: int
    center: tuple[float, float, float]
    radius: float

    def mitsuba_shape(self, material: str, world_to_frame: np.ndarray | None = None):
        """A Mitsuba analytic sphere with the named probe material (:data:`PROBE_MATERIALS`).

        ``world_to_frame``: a (4, 4) similarity (rotation, uniform scale, translation); the
        radius scales with it."""
        from roomlight.core.render.materials import material as probe_bsdf
        from roomlight.core.render.variant import mitsuba

        mi = mitsuba()
        c = np.asarray(self.center, np.float64)
        r = float(self.radius)
        if world_to_frame is not None:
            c = transform_points(world_to_frame, c)[0]
            r *= float(np.cbrt(np.linalg.det(np.asarray(world_to_frame, np.float64)[:3, :3])))
        return mi.load_dict({"type": "sphere", "center": [float(x) for x in c], "radius": r,
                             "bsdf": probe_bsdf(material)})

    def to_dict(self) -> dict:
        return {"id": self.id, "label": self.label, "center": [float(c) for c in self.center],
                "radius": float(self.radius)}

    @classmethod
    def from_dict(cls, d: dict) -> ProbeSphere:
        return cls(str(d["id"]), int(d["label"]), tuple(float(c) for c in d["center"]), float(d["radius"]))
