"""The room description: plain dataclasses that serialise to JSON.

A :class:`Room` is everything needed to rebuild the 3-D scene (``roomlight.datagen.synth.scene``) and
to render the panorama (``roomlight.datagen.synth.camera``). Units: metres; the world frame has **y up**,
the floor at y = 0; radiance (emission, sky) is linear Rec.709 RGB scaled so that its
luminance is in cd/m^2 (nits); albedos are linear RGB in [0, 1].

Surfaces are built from five primitives (:class:`Quad`, :class:`Box`, :class:`Cylinder`,
:class:`Disk`, :class:`Sphere`). A primitive's *visible side* matters: Mitsuba's BSDFs and
area emitters are one-sided, so shell quads face into the room and solids face outwards.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

__all__ = [
    "GENERATOR_VERSION",
    "Box",
    "Cylinder",
    "Disk",
    "Door",
    "Furniture",
    "Light",
    "Material",
    "Part",
    "Quad",
    "Room",
    "Sky",
    "Sphere",
    "Vec3",
    "Window",
    "part_from_dict",
]

#: Bumped whenever the same seed would produce a different room (2: furniture footprints include
#: every part, so plant foliage keeps 0.4 m from the capture point; the sun is put in view of a
#: window in 40 % of sunny rooms; 3: large spaces with high ceilings and high-bay lights, larger
#: and clerestory windows, continuous 2700-6500 K light colours, wider sky and sun strengths,
#: concrete floors).
GENERATOR_VERSION = "3"

Vec3 = tuple[float, float, float]


def _vec(v) -> Vec3:
    return tuple(float(x) for x in v)  # type: ignore[return-value]


@dataclass
class Material:
    """A surface material.

    Attributes:
        name: unique key within the room.
        bsdf: ``diffuse``, ``plastic`` (rough dielectric coating over ``albedo``), ``metal``
            (rough conductor tinted by ``albedo``) or ``black`` (absorbs everything; emitters).
        albedo: linear RGB reflectance in [0, 1] (plastic: the diffuse base; metal: the tint).
        roughness: GGX alpha of plastic / metal (0.02 = polished, 0.4 = satin).
        texture: procedural pattern multiplying ``albedo`` (see ``roomlight.datagen.synth.textures``):
            ``{"pattern": ..., "tile": metres, "seed": int, ...}``, or None.
        emission: radiance (nits, linear RGB) emitted from the visible side, or None.
        emission_texture: procedural pattern multiplying ``emission`` (screens), or None.
    """

    name: str
    bsdf: str = "diffuse"
    albedo: Vec3 = (0.5, 0.5, 0.5)
    roughness: float = 0.2
    texture: dict | None = None
    emission: Vec3 | None = None
    emission_texture: dict | None = None

    def __post_init__(self):
        self.albedo = _vec(self.albedo)
        if self.emission is not None:
            self.emission = _vec(self.emission)


@dataclass
class Quad:
    """Parallelogram ``origin + s * edge_a + t * edge_b`` (s, t in [0, 1]); visible side = edge_a x edge_b.

    ``uv`` is ``"world"`` (texture coordinates are world metres, continuous across quads) or
    ``"local"`` ((s, t), for pictures and screens; t = 0 at the top edge).
    """

    origin: Vec3
    edge_a: Vec3
    edge_b: Vec3
    material: str
    uv: str = "world"
    shape: str = "quad"


@dataclass
class Box:
    """Axis-aligned solid box ``lo``..``hi`` (outward faces); ``faces`` lists which of
    ``-x +x -y +y -z +z`` (letters ``xXyYzZ``) are built (e.g. drop ``y`` when it rests on the floor)."""

    lo: Vec3
    hi: Vec3
    material: str
    faces: str = "xXyYzZ"
    shape: str = "box"


@dataclass
class Cylinder:
    """Vertical solid cylinder from ``base`` (centre of the bottom) up by ``height``; outward
    side, plus caps when ``caps`` (``"both"``, ``"top"``, ``"bottom"`` or ``"none"``)."""

    base: Vec3
    radius: float
    height: float
    material: str
    caps: str = "both"
    shape: str = "cylinder"


@dataclass
class Disk:
    """Horizontal disk at ``center`` facing up (``facing = +1``) or down (``-1``)."""

    center: Vec3
    radius: float
    material: str
    facing: float = -1.0
    shape: str = "disk"


@dataclass
class Sphere:
    """Sphere (outward side)."""

    center: Vec3
    radius: float
    material: str
    shape: str = "sphere"


Part = Quad | Box | Cylinder | Disk | Sphere
_PART_TYPES = {"quad": Quad, "box": Box, "cylinder": Cylinder, "disk": Disk, "sphere": Sphere}


def part_from_dict(d: dict) -> Part:
    """Inverse of ``dataclasses.asdict`` for any :data:`Part`."""
    kind = d["shape"]
    cls = _PART_TYPES[kind]
    kw = {k: (tuple(v) if isinstance(v, list) else v) for k, v in d.items()}
    return cls(**kw)


@dataclass
class Furniture:
    """A piece of furniture (or a light fixture): its kind, bounding box and parts."""

    kind: str
    lo: Vec3
    hi: Vec3
    parts: list = field(default_factory=list)


@dataclass
class Light:
    """An artificial light source: which material emits, where, and whether it is switched on.

    ``power`` is the emitted flux estimate pi * area * luminance (lumen-like units) used for
    emitter sampling weights; ``center`` locates it for summaries and checks.
    """

    kind: str
    material: str
    center: Vec3
    power: float
    on: bool = True


@dataclass
class Window:
    """A window opening: the inner hole ``origin + s * edge_a + t * edge_b`` in the wall plane
    (``edge_a`` horizontal, ``edge_b`` up), the inward wall normal ``normal`` and the reveal
    depth (wall thickness). The outdoor environment shows through the *portal*, the same
    rectangle moved ``depth`` outwards."""

    origin: Vec3
    edge_a: Vec3
    edge_b: Vec3
    normal: Vec3
    depth: float


@dataclass
class Door:
    """A door in a wall: ``closed`` (a door leaf fills it) or open into an adjacent space."""

    origin: Vec3
    edge_a: Vec3
    edge_b: Vec3
    normal: Vec3
    depth: float
    state: str  # "closed" | "open"
    space: tuple | None = None  # adjacent space box (x0, z0, x1, z1, height) when open


@dataclass
class Sky:
    """The outdoor environment seen through windows (radiance at infinity, nits).

    The sky radiance at elevation e above the horizon is
    ``horizon + (zenith - horizon) * sin(e) ** exponent`` plus a circumsolar glow
    ``glow * exp(-gamma / glow_width)`` (gamma = angle to the sun, radians); below the horizon
    it is ``ground``. ``skyline`` holds per-azimuth-bin obstruction heights as sin(elevation)
    (bins of equal azimuth over [0, 2 pi), azimuth measured like the panorama's u:
    atan2(x, -z)), and ``facade`` their radiance. The sun is a disk of angular radius
    ``sun_radius_deg`` and radiance ``sun`` in direction ``sun_dir`` (towards the sun), or
    absent (``sun = None``: below the horizon, behind the skyline, or overcast).
    """

    kind: str  # clear | overcast | dusk | night
    zenith: Vec3
    horizon: Vec3
    exponent: float
    ground: Vec3
    glow: Vec3 = (0.0, 0.0, 0.0)
    glow_width: float = 0.3
    sun: Vec3 | None = None
    sun_dir: Vec3 = (0.0, 1.0, 0.0)
    sun_radius_deg: float = 0.5
    sun_illuminance: float = 0.0
    skyline: list = field(default_factory=list)
    facade: list = field(default_factory=list)  # list of RGB triples, one per bin


@dataclass
class Room:
    """A complete procedural room (see the module docstring for units and frames).

    Attributes:
        seed: the generator seed; ``generate_room(seed)`` reproduces the room exactly.
        shell: ``box``, ``L`` or ``alcove``. ``room_type``: living, bedroom, office, kitchen, hall.
        lighting: scenario (``sunny``, ``overcast``, ``dusk``, ``night``, ``interior``).
        height: ceiling height. ``cells``: floor plan as disjoint rectangles (x0, z0, x1, z1).
        capture: the panorama's capture point. ``yaw``: rotation (radians, about +y) of the
            panorama's frame: pixel direction omega maps to the world direction R_y(yaw) omega.
        materials: by name. ``shell_parts``: walls, floor, ceiling, reveals, adjacent spaces.
        furniture: pieces (lights included); ``lights``: the artificial light sources.
        windows / doors: openings; ``sky``: outdoor environment (None when no window).
    """

    seed: int
    shell: str
    room_type: str
    lighting: str
    height: float
    cells: list
    capture: Vec3
    yaw: float
    materials: dict = field(default_factory=dict)
    shell_parts: list = field(default_factory=list)
    furniture: list = field(default_factory=list)
    lights: list = field(default_factory=list)
    windows: list = field(default_factory=list)
    doors: list = field(default_factory=list)
    sky: Sky | None = None
    version: str = GENERATOR_VERSION

    def all_parts(self) -> list:
        """Every primitive of the room: shell parts, then furniture parts in order."""
        out = list(self.shell_parts)
        for f in self.furniture:
            out.extend(f.parts)
        return out

    def emitters(self) -> list:
        """Names of the materials that emit light in this room (lit artificial lights)."""
        return [n for n, m in self.materials.items() if m.emission is not None and max(m.emission) > 0]

    def to_dict(self, full: bool = True) -> dict:
        """JSON-ready dict. ``full=False`` drops the primitive lists (furniture keeps kind and
        bounding box) so it fits in a file header; the room is still reproducible from ``seed``."""
        d = asdict(self)
        if not full:
            d.pop("shell_parts")
            for f in d["furniture"]:
                f.pop("parts")
            if d["sky"] is not None:
                d["sky"].pop("skyline")
                d["sky"].pop("facade")
        return d

    @classmethod
    def from_dict(cls, d: dict) -> Room:
        """Rebuild a room from :meth:`to_dict` (``full=True``) output."""
        d = dict(d)
        d["materials"] = {k: Material(**v) for k, v in d["materials"].items()}
        d["shell_parts"] = [part_from_dict(p) for p in d.get("shell_parts", [])]
        d["furniture"] = [Furniture(kind=f["kind"], lo=tuple(f["lo"]), hi=tuple(f["hi"]),
                                    parts=[part_from_dict(p) for p in f.get("parts", [])])
                          for f in d["furniture"]]
        d["lights"] = [Light(**x) for x in d["lights"]]
        d["windows"] = [Window(**x) for x in d["windows"]]
        d["doors"] = [Door(**x) for x in d["doors"]]
        d["sky"] = Sky(**d["sky"]) if d.get("sky") else None
        d["capture"] = tuple(d["capture"])
        return cls(**d)
