"""Object placement of the synthetic benchmark for one panorama (supplementary "Synthetic scene design").

Protocol, per panorama:

1. The camera sits at the panorama's capture point (the origin), ``fov`` = 65 degrees
   (horizontal), looking along -z with +y up.
2. Three square screen-space boxes of side 0.25-0.35 x the frame width are drawn uniformly
   inside the frame, rejecting draws until no two boxes overlap.
3. Each box gets one object: two non-convex shapes (the input view) and a probe sphere (the
   evaluation view). The strata of relative depth [0.05, 0.25], [0.4, 0.6], [0.75, 0.95] are
   dealt to the three objects in random order, and a fraction ``f`` is drawn in each.
4. An object (randomly rotated; the probe is not) is scaled so that the perspective projection of
   all its vertices fits its box, touching at least one side. The scale is proportional to the
   object's distance ``t`` along the box's centre ray (projection into a box is scale-invariant
   about the camera), so the object's *shape in the image* is fixed before its depth is chosen:
   the object is ``t * (c + kappa * R V)`` for centre direction ``c``, unit-bounding-radius
   vertices ``V`` and relative radius ``kappa`` (capped at ``max_relative_radius``).
5. **Depth range.** Along the centre ray, the range is ``[0, t_max]``, where ``t_max`` is the
   largest distance at which the object's bounding sphere (radius ``kappa t``) still lies inside
   the emitter mesh with a clearance of ``margin`` (a fraction of the emitter distance). It is
   measured by casting rays against the 2.5D area light mesh over the whole cone of directions
   the bounding sphere subtends (spaced at most half an emitter pixel apart): for a direction
   ``d`` at angle ``beta`` from ``c`` the sphere's far side lies at ``t g(beta)``,
   ``g = cos(beta) + sqrt(kappa^2 - sin(beta)^2)``, so ``t_max = (1 - margin) min_d D(d) / g``.
   The object is placed at ``t = f t_max``; it is therefore inside the emitter by construction.

All positions are in metres in the capture frame (y up), as is the panorama depth.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
import torch

from roomlight.evaluation.harness.errors import BenchError

__all__ = ["PlacementError", "PlacementConfig", "ScreenBox", "PlacedObject", "EmitterProbe", "sample_boxes",
           "box_planes", "relative_radius", "cone_directions", "max_inside_distance", "random_rotation",
           "place_objects", "NONCONVEX_SHAPES", "STRATA"]

#: Built-in shapes that stand in for the paper's bunny and armadillo.
NONCONVEX_SHAPES = ("knot", "blob", "torus", "cup", "spiky")
#: The paper's depth strata (fractions of the depth range).
STRATA = ((0.05, 0.25), (0.4, 0.6), (0.75, 0.95))


class PlacementError(BenchError):
    """The protocol cannot place the objects in a panorama (e.g. an emitter too close to the camera)."""


@dataclass(frozen=True)
class PlacementConfig:
    """Settings of the placement protocol (defaults: the paper's)."""

    fov: float = 65.0                                  #: horizontal field of view, degrees
    width: int = 128                                   #: image width, pixels
    height: int = 128                                  #: image height, pixels
    box_range: tuple[float, float] = (0.25, 0.35)      #: box side, fraction of the frame width
    strata: tuple[tuple[float, float], ...] = STRATA   #: relative depth strata, one per object
    margin: float = 0.05                               #: clearance to the emitter, fraction of its distance
    max_relative_radius: float = 0.5                   #: cap on bounding radius / centre distance
    min_surface_distance: float = 0.02                 #: nearest object surface to the camera, metres
    max_tries: int = 10000                             #: box draws before giving up

    def to_dict(self) -> dict:
        return asdict(self)


@dataclass(frozen=True)
class ScreenBox:
    """An axis-aligned box in normalised frame coordinates: x in [0, 1] left to right, y in [0, 1]
    top to bottom (pixel (i, j) of an h x w image covers x in [j/w, (j+1)/w], y in [i/h, (i+1)/h])."""

    x0: float
    y0: float
    x1: float
    y1: float

    def overlaps(self, other: ScreenBox) -> bool:
        return self.x0 < other.x1 and other.x0 < self.x1 and self.y0 < other.y1 and other.y0 < self.y1

    @property
    def centre(self) -> tuple[float, float]:
        return 0.5 * (self.x0 + self.x1), 0.5 * (self.y0 + self.y1)

    def to_list(self) -> list[float]:
        return [self.x0, self.y0, self.x1, self.y1]


@dataclass
class PlacedObject:
    """One placed object and how it was placed (all lengths in metres)."""

    id: str
    role: str                       #: "input" (fitted view) or "probe" (evaluation view)
    shape: str | None               #: built-in shape name, or None for a mesh file
    mesh: str | None                #: mesh file path, or None
    box: ScreenBox
    stratum: tuple[float, float]
    fraction: float                 #: f, the relative depth drawn in the stratum
    distance: float                 #: t = f * t_max, centre distance along the box's centre ray
    max_distance: float             #: t_max of the depth range [0, t_max]
    emitter_distance: float         #: distance to the emitter mesh along the centre ray
    relative_radius: float          #: kappa = bounding radius / t
    translate: tuple[float, float, float] = (0.0, 0.0, 0.0)
    scale: float = 1.0
    rotate: tuple[float, float, float, float] = (0.0, 1.0, 0.0, 0.0)

    @property
    def radius(self) -> float:
        """Bounding-sphere radius in metres."""
        return self.relative_radius * self.distance

    def to_dict(self) -> dict:
        d = asdict(self)
        d["box"] = self.box.to_list()
        d["radius"] = self.radius
        return d

    def object_spec(self, material):
        """The :class:`~roomlight.fitting.scene.ObjectSpec` of this object with ``material``."""
        from pathlib import Path

        from roomlight.fitting.scene.description import ObjectSpec

        return ObjectSpec(id=self.id, shape=self.shape, mesh=Path(self.mesh) if self.mesh else None,
                          translate=tuple(self.translate), scale=self.scale, rotate=tuple(self.rotate),
                          material=material)


# ----------------------------------------------------------------------------------- emitter
class EmitterProbe:
    """Distances from the capture point to a 2.5D area light mesh, by Mitsuba ray casting.

    Args:
        depth: (H, W) radial depth in metres (the emitter's radiance plays no role here).
    """

    def __init__(self, depth: torch.Tensor):
        from roomlight.core.render.scene import EmitterScene

        d = depth.float()
        self.depth = d
        self.resolution = tuple(d.shape)
        self.escene = EmitterScene("mesh", self.resolution)
        self.escene.set_emitter(torch.ones(*self.resolution, 3), d)

    def distance(self, directions: np.ndarray) -> np.ndarray:
        """(N,) distance along each direction (N, 3) from the origin to the emitter mesh, metres.

        A ray that misses the (closed) mesh, which can only happen through round-off at a
        seam, falls back to the bilinearly sampled depth map.
        """
        mi = self.escene.mi
        d = np.asarray(directions, np.float64)
        d = d / np.linalg.norm(d, axis=-1, keepdims=True)
        direction = mi.Vector3f(*[mi.Float(d[:, k].astype(np.float32)) for k in range(3)])
        ray = mi.Ray3f(mi.Point3f(0.0, 0.0, 0.0), direction)
        si = self.escene.scene.ray_intersect(ray)
        t = np.array(si.t, dtype=np.float64)
        miss = ~np.isfinite(t)
        if miss.any():
            from roomlight.core.geometry.equirect import sample_equirect

            fb = sample_equirect(self.depth[None, None].double(), torch.from_numpy(d[miss]))[0, 0].numpy()
            t[miss] = fb
        return t


# ----------------------------------------------------------------------------------- screen
def sample_boxes(rng: np.random.Generator, n: int, config: PlacementConfig) -> list[ScreenBox]:
    """``n`` non-overlapping square boxes inside the frame, sides uniform in ``box_range``."""
    aspect = config.width / config.height
    lo, hi = config.box_range
    for _ in range(config.max_tries):
        boxes: list[ScreenBox] = []
        for _k in range(n):
            s = rng.uniform(lo, hi)
            sh = s * aspect
            if sh > 1.0:
                raise PlacementError(f"placement: a box of {s:.2f} x the frame width does not fit the frame height "
                                     f"({config.width}x{config.height})")
            x0, y0 = rng.uniform(0.0, 1.0 - s), rng.uniform(0.0, 1.0 - sh)
            b = ScreenBox(x0, y0, x0 + s, y0 + sh)
            if any(b.overlaps(o) for o in boxes):
                break
            boxes.append(b)
        if len(boxes) == n:
            return boxes
    raise PlacementError(f"placement: found no {n} non-overlapping boxes of side {lo}-{hi} in {config.max_tries} tries")


def _tan_half(config: PlacementConfig) -> tuple[float, float]:
    tx = math.tan(math.radians(config.fov) / 2.0)
    return tx, tx * config.height / config.width


def _basis(forward=(0.0, 0.0, -1.0), up=(0.0, 1.0, 0.0)) -> np.ndarray:
    from roomlight.core.geometry.projection import camera_basis

    return camera_basis(forward, up).numpy()  # rows: right, up, forward


def box_planes(box: ScreenBox, config: PlacementConfig,
               basis: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The box's viewing pyramid.

    Returns:
        normals: (4, 3) unit normals (world frame) of the pyramid's planes through the camera,
        pointing inwards (a point p projects inside the box iff normals @ p >= 0);
        centre: (3,) unit direction through the box centre.
    """
    b = _basis() if basis is None else basis
    tx, ty = _tan_half(config)
    x0, x1 = (2 * box.x0 - 1) * tx, (2 * box.x1 - 1) * tx
    ylo, yhi = (1 - 2 * box.y1) * ty, (1 - 2 * box.y0) * ty
    n_cam = np.array([[1.0, 0.0, -x0], [-1.0, 0.0, x1], [0.0, 1.0, -ylo], [0.0, -1.0, yhi]])
    n_cam /= np.linalg.norm(n_cam, axis=1, keepdims=True)
    cx, cy = box.centre
    c_cam = np.array([(2 * cx - 1) * tx, (1 - 2 * cy) * ty, 1.0])
    c_cam /= np.linalg.norm(c_cam)
    return n_cam @ b, c_cam @ b


def relative_radius(vertices: np.ndarray, normals: np.ndarray, centre: np.ndarray) -> float:
    """Largest ``kappa`` such that ``centre + kappa * vertices`` lies in the pyramid ``normals``.

    Args:
        vertices: (N, 3) object vertices, centred, bounding radius 1 (already rotated).
        normals: (4, 3) inward plane normals; centre: (3,) unit direction inside the pyramid.
    """
    nc = normals @ centre                # (4,) > 0
    nv = vertices @ normals.T            # (N, 4)
    with np.errstate(divide="ignore"):
        bound = np.where(nv < 0, nc[None, :] / np.maximum(-nv, 1e-12), np.inf)
    return float(bound.min())


def cone_directions(centre: np.ndarray, half_angle: float, spacing: float) -> np.ndarray:
    """Directions (N, 3) covering the cone of ``half_angle`` around ``centre`` (rim included),
    at most ``spacing`` radians apart."""
    c = centre / np.linalg.norm(centre)
    a = np.array([1.0, 0.0, 0.0]) if abs(c[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = np.cross(c, a)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(c, e1)
    rings = max(2, math.ceil(half_angle / spacing))
    out = [c[None]]
    for r in range(1, rings + 1):
        beta = half_angle * r / rings
        m = max(6, math.ceil(2 * math.pi * math.sin(beta) / spacing))
        phi = 2 * math.pi * (np.arange(m) + 0.5 * (r % 2)) / m
        out.append(math.cos(beta) * c + math.sin(beta) * (np.cos(phi)[:, None] * e1 + np.sin(phi)[:, None] * e2))
    return np.concatenate(out)


def max_inside_distance(probe: EmitterProbe, centre: np.ndarray, kappa: float, margin: float) -> tuple[float, float]:
    """``(t_max, emitter distance along centre)`` for a bounding sphere of radius ``kappa t`` centred
    at ``t * centre`` (see the module docstring, step 5)."""
    h = probe.resolution[0]
    alpha = math.asin(min(kappa, 1.0 - 1e-9))
    dirs = cone_directions(centre, alpha, 0.5 * math.pi / h)
    dist = probe.distance(dirs)
    cosb = np.clip(dirs @ centre, -1.0, 1.0)
    sin2 = np.clip(1.0 - cosb ** 2, 0.0, None)
    g = cosb + np.sqrt(np.clip(kappa ** 2 - sin2, 0.0, None))
    t_max = (1.0 - margin) * float(np.min(dist / g))
    return t_max, float(dist[0])


def random_rotation(rng: np.random.Generator) -> tuple[float, float, float, float]:
    """A uniformly random rotation as (axis x, y, z, angle in degrees)."""
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    if q[0] < 0:
        q = -q
    angle = 2.0 * math.degrees(math.acos(min(1.0, q[0])))
    axis = q[1:] / max(np.linalg.norm(q[1:]), 1e-12)
    return (float(axis[0]), float(axis[1]), float(axis[2]), float(angle))


def _unit_geometry(shape: str | None, mesh: str | None, rotate) -> tuple[np.ndarray, np.ndarray, float]:
    """(rotated, centred, unit-radius vertices (N, 3); original bbox centre (3,); bounding radius)."""
    from pathlib import Path

    from roomlight.fitting.scene.build import object_geometry
    from roomlight.fitting.scene.description import ObjectSpec

    raw = ObjectSpec(id="tmp", shape=shape, mesh=Path(mesh) if mesh else None)
    v, _ = object_geometry(raw)
    c0 = 0.5 * (v.max(0) + v.min(0))
    r0 = float(np.linalg.norm(v - c0, axis=1).max())
    return ((v - c0) / r0) @ _unit_rotation(rotate).T, c0, r0


def place_objects(probe: EmitterProbe, rng: np.random.Generator, input_shapes, config: PlacementConfig,
                  probe_shape: str = "sphere") -> list[PlacedObject]:
    """Place two input-view objects and the probe for one panorama (module docstring, steps 2-5).

    Args:
        probe: the panorama's emitter (distances to its mesh).
        rng: the random source (seeded by the caller per panorama).
        input_shapes: two entries, each a built-in shape name or a path to a .ply/.obj mesh.
        config: protocol settings.
    Returns:
        [input object 1, input object 2, probe], each with its ObjectSpec transform filled in.
    """
    from roomlight.fitting.scene.shapes import BUILTIN_SHAPES

    if len(input_shapes) != 2:
        raise PlacementError(f"placement: the input view needs exactly two shapes, got {len(input_shapes)}")
    if len(config.strata) != 3:
        raise PlacementError(f"placement: need three depth strata, got {len(config.strata)}")
    boxes = sample_boxes(rng, 3, config)
    order = rng.permutation(3)
    basis = _basis()
    placed = []
    used: set[str] = set()
    entries = [(s, "input") for s in input_shapes] + [(probe_shape, "probe")]
    for k, (entry, role) in enumerate(entries):
        builtin = entry in BUILTIN_SHAPES
        name = entry if builtin else _stem(entry)
        oid = "probe" if role == "probe" else name
        while oid in used:
            oid += "_2"
        used.add(oid)
        rotate = random_rotation(rng) if role == "input" else (0.0, 1.0, 0.0, 0.0)
        unit_v, c0, r0 = _unit_geometry(entry if builtin else None, None if builtin else str(entry), rotate)
        normals, centre = box_planes(boxes[k], config, basis)
        kappa = min(relative_radius(unit_v, normals, centre), config.max_relative_radius)
        t_max, d_centre = max_inside_distance(probe, centre, kappa, config.margin)
        stratum = tuple(config.strata[order[k]])
        f = float(rng.uniform(*stratum))
        t = f * t_max
        if t * (1.0 - kappa) < config.min_surface_distance:
            raise PlacementError(
                f"placement: object {oid!r} would come {t * (1 - kappa):.3f} m from the camera (minimum "
                f"{config.min_surface_distance} m); the emitter is only {d_centre:.2f} m away along its box")
        scale = kappa * t / r0
        rot = _unit_rotation(rotate)
        translate = t * centre - scale * (rot @ c0)
        placed.append(PlacedObject(
            id=oid, role=role, shape=entry if builtin else None, mesh=None if builtin else str(entry),
            box=boxes[k], stratum=stratum, fraction=f, distance=t, max_distance=t_max,
            emitter_distance=d_centre, relative_radius=kappa, translate=tuple(float(x) for x in translate),
            scale=float(scale), rotate=tuple(float(x) for x in rotate)))
    return placed


def _unit_rotation(rotate) -> np.ndarray:
    from roomlight.fitting.scene.description import ObjectSpec

    return ObjectSpec(id="tmp", shape="sphere", rotate=tuple(rotate)).matrix()[:3, :3]


def _stem(path) -> str:
    from pathlib import Path

    return Path(str(path)).stem
