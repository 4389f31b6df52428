"""Where the capacity experiment puts its probes, panorama viewpoints and cameras in a room.

The protocol (supplementary, "Capacity of a single 2.5D area light"): three probe spheres A, B, C
in free space; panoramas are captured at the centre of A, the centre of B and their midpoint M
(without the probes in the room), and each probe is seen by its own close-up camera.

Everything is decided by ray casting against the room's Mitsuba scene (probes absent):

- a probe centre (and M) keeps ``clearance`` metres from every surface (rays in 128 directions);
- A and B are 1 to 2.5 m apart and see each other; C is at least 0.8 m from both and is seen
  from A, B and M, so every probe lies inside every viewpoint's 2.5D light (a probe hidden from a
  viewpoint would sit behind that light's surface, which no panorama-based light can fix);
- a probe's camera looks at it from ``camera_distance`` (5 probe radii by default), 15 degrees
  above the horizon, from the first of 16 azimuths whose whole line of sight to the sphere is
  clear and which lies inside every emitter the probes are relit by: seen from every capture
  point (so inside each 2.5D light) and inside each capture point's sphere proxy (a camera
  outside an emitter would look at its back); the room's geometry decides the rest (the masks of
  :mod:`roomlight.evaluation.experiments.capacity` keep only pixels where the probe is the first hit).

Positions are world coordinates in metres (y up). :func:`wall_light_room` is a fixed room with
a wall light next to the probes, the case where the 2.5D light must beat an environment map.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from roomlight.errors import RoomlightError
from roomlight.core.render.raycast import RayCaster, sphere_directions

__all__ = ["ProbeLayout", "LayoutConfig", "Caster", "place_layout", "cameras_for", "sphere_proxy_radius", "wall_light_room", "wall_light_layout"]


@dataclass(frozen=True)
class LayoutConfig:
    """Geometry of the probes and cameras (metres, degrees)."""

    probe_radius: float = 0.12       #: radius of the three probe spheres
    clearance: float = 0.35          #: free space around probe centres and the midpoint
    pair_distance: tuple[float, float] = (1.0, 2.5)  #: allowed distance between A and B
    third_distance: float = 0.8      #: C keeps at least this distance from A and B
    camera_distance: float = 0.6     #: camera to probe centre
    camera_elevation: float = 15.0   #: camera height above the probe, as an angle
    camera_fov: float = 30.0         #: horizontal field of view of the probe cameras
    sphere_margin: float = 0.2       #: the sphere proxy's enlargement (cameras must fit inside it)
    height_range: tuple[float, float] = (0.5, 1.7)  #: probe centre heights above the floor
    tries: int = 400                 #: candidate positions drawn before a room is given up


@dataclass
class ProbeLayout:
    """Probes, viewpoints and cameras of one room (world frame, metres).

    Attributes:
        probes: (3, 3) centres of A, B, C. ``radius``: their radius.
        viewpoints: (3, 3) capture points: centre of A, centre of B, midpoint of A and B.
        cameras: one (origin, target) pair per probe (target = the probe centre).
        fov: horizontal field of view of the probe cameras, degrees.
    """

    probes: np.ndarray
    radius: float
    viewpoints: np.ndarray
    cameras: list = field(default_factory=list)
    fov: float = 30.0

    VIEWPOINT_NAMES = ("centre of A", "centre of B", "midpoint")

    def to_dict(self) -> dict:
        return {"probes": self.probes.round(5).tolist(), "radius": self.radius,
                "viewpoints": self.viewpoints.round(5).tolist(), "viewpoint_names": list(self.VIEWPOINT_NAMES),
                "cameras": [[np.round(o, 5).tolist(), np.round(t, 5).tolist()] for o, t in self.cameras],
                "fov": self.fov}

    @classmethod
    def from_dict(cls, d: dict) -> "ProbeLayout":
        return cls(np.asarray(d["probes"], np.float64), float(d["radius"]), np.asarray(d["viewpoints"], np.float64),
                   [(np.asarray(o, np.float64), np.asarray(t, np.float64)) for o, t in d["cameras"]],
                   float(d["fov"]))


class Caster(RayCaster):
    """Ray casts against a room's Mitsuba scene, with the questions the probe layout asks of them."""

    def clearance(self, point, n: int = 128) -> float:
        """Distance from ``point`` to the nearest surface over ``n`` directions (inf-safe: a ray
        escaping the room counts as 0, so points outside a closed room are refused)."""
        t = self.distances(point, sphere_directions(n))
        return 0.0 if not np.isfinite(t).all() else float(t.min())

    def sees(self, p, q, slack: float = 1e-3) -> bool:
        """True when the segment from ``p`` to ``q`` crosses no surface."""
        p, q = np.asarray(p, np.float64), np.asarray(q, np.float64)
        dist = float(np.linalg.norm(q - p))
        if dist < 1e-9:
            return True
        return bool(self.distances(p, (q - p)[None])[0] >= dist - slack)


def _candidate(rng, room, cfg: LayoutConfig) -> np.ndarray:
    cells = np.asarray(room.cells, np.float64)
    area = (cells[:, 2] - cells[:, 0]) * (cells[:, 3] - cells[:, 1])
    x0, z0, x1, z1 = cells[int(rng.choice(len(cells), p=area / area.sum()))]
    m = cfg.clearance
    lo, hi = cfg.height_range
    y = rng.uniform(lo, max(lo, min(hi, room.height - m)))
    return np.array([rng.uniform(x0 + m, max(x0 + m, x1 - m)), y, rng.uniform(z0 + m, max(z0 + m, z1 - m))])


def place_layout(room, caster: Caster, rng: np.random.Generator, cfg: LayoutConfig = LayoutConfig()) -> ProbeLayout:
    """Probes A, B, C, the three viewpoints and the cameras for ``room`` (see the module docstring).

    Raises:
        RoomlightError: no valid placement within ``cfg.tries`` candidates (a cluttered room).
    """
    free = []
    for _ in range(cfg.tries):
        p = _candidate(rng, room, cfg)
        if caster.clearance(p) >= cfg.clearance:
            free.append(p)
        if len(free) >= 24:
            break
    lo, hi = cfg.pair_distance
    for i, a in enumerate(free):
        for b in free[i + 1:]:
            ab = float(np.linalg.norm(b - a))
            if not (lo <= ab <= hi) or not caster.sees(a, b):
                continue
            m = 0.5 * (a + b)
            if caster.clearance(m) < cfg.clearance:
                continue
            for c in free:
                if min(np.linalg.norm(c - a), np.linalg.norm(c - b)) < cfg.third_distance:
                    continue
                if not all(caster.sees(v, c) for v in (a, b, m)):
                    continue
                probes = np.stack([a, b, c])
                layout = ProbeLayout(probes, cfg.probe_radius, np.stack([a, b, m]), fov=cfg.camera_fov)
                cams = cameras_for(layout, caster, cfg)
                if cams is None:
                    continue
                layout.cameras = cams
                return layout
    raise RoomlightError(f"room {getattr(room, 'seed', '?')}: no free place for three probes "
                         f"({len(free)} free candidates of {cfg.tries})")


def sphere_proxy_radius(probes, radius: float, viewpoint, margin: float) -> float:
    """Radius of the sphere proxy at ``viewpoint``: the smallest sphere around it holding every
    probe (centres ``probes`` (P, 3), radius ``radius``), enlarged by ``margin`` (the benchmark's
    rule for its sphere-proxy baseline)."""
    v = np.asarray(viewpoint, np.float64)
    return max(float(np.linalg.norm(np.asarray(p) - v)) + radius for p in probes) * (1.0 + margin)


def _inside_emitters(caster: Caster, layout: ProbeLayout, origin, margin: float) -> bool:
    """``origin`` is seen from every capture point (inside each 2.5D light) and 5 cm or more
    inside each capture point's sphere proxy."""
    for v in layout.viewpoints:
        if not caster.sees(v, origin):
            return False
        if np.linalg.norm(origin - v) > sphere_proxy_radius(
                layout.probes, layout.radius, v, margin) - 0.05:
            return False
    return True


def _look_from(azimuth: float, elevation_deg: float) -> np.ndarray:
    e = math.radians(elevation_deg)
    return np.array([math.cos(e) * math.sin(azimuth), math.sin(e), -math.cos(e) * math.cos(azimuth)])


def _clear_view(caster: Caster, origin, centre, radius: float, others, other_radius: float) -> bool:
    """The camera at ``origin`` sees the whole sphere: its centre and four silhouette points are
    unobstructed by the room, and no other probe stands within the view cone."""
    d = centre - origin
    dist = float(np.linalg.norm(d))
    d /= dist
    up = np.array([0.0, 1.0, 0.0])
    side = np.cross(d, up)
    side /= np.linalg.norm(side)
    up2 = np.cross(side, d)
    pts = [centre] + [centre + radius * s for s in (side, -side, up2, -up2)]
    if not all(caster.sees(origin, p - 0.5 * radius * d) for p in pts):
        return False
    for q in others:  # another probe between the camera and this one, or around the camera
        v = q - origin
        along = float(v @ d)
        if 0 < along < dist and np.linalg.norm(v - along * d) < radius + other_radius + 0.02:
            return False
        if np.linalg.norm(v) < other_radius + 0.1:
            return False
    return True


def cameras_for(layout: ProbeLayout, caster: Caster, cfg: LayoutConfig = LayoutConfig()) -> list | None:
    """One (origin, target) per probe with a clear view of it, or None when some probe has none."""
    cams = []
    for k, p in enumerate(layout.probes):
        others = [q for j, q in enumerate(layout.probes) if j != k]
        found = None
        for step in range(16):
            az = 2.0 * math.pi * step / 16
            o = p + cfg.camera_distance * _look_from(az, cfg.camera_elevation)
            if caster.clearance(o, 64) < 0.08:
                continue
            if (_clear_view(caster, o, p, layout.radius, others, layout.radius)
                    and _inside_emitters(caster, layout, o, cfg.sphere_margin)):
                found = (o, p.copy())
                break
        if found is None:
            return None
        cams.append(found)
    return cams


# ---------------------------------------------------------------------------------------------
# A fixed room: probes next to a wall light
# ---------------------------------------------------------------------------------------------

def wall_light_room():
    """A 5 x 2.7 x 4 m room lit by one 0.4 m square wall light (3000 nits) and a dim ceiling
    panel, with a cabinet standing in a corner. The probes of :func:`wall_light_layout` stand
    0.8 m from the wall light, so its direction and distance change strongly between them: the
    case an environment map cannot represent and a 2.5D light can."""
    from roomlight.datagen.synth.rooms import box_room
    from roomlight.datagen.synth.spec import Box, Furniture, Light, Material, Quad

    room = box_room(size=(5.0, 2.7, 4.0), capture=(2.5, 1.4, 2.0), albedo=(0.55, 0.55, 0.55), light=False)
    room.seed = 0
    room.room_type = "wall light test room"
    room.materials["lamp"] = Material("lamp", "black", emission=(3000.0, 2800.0, 2400.0))
    room.materials["panel"] = Material("panel", "black", emission=(150.0, 150.0, 150.0))
    room.materials["wood"] = Material("wood", "diffuse", (0.45, 0.28, 0.15))
    # Visible side = edge_a x edge_b: (0, 1, 0) x (0, 0, 1) = +x, into the room.
    room.furniture.append(Furniture("wall_light", (0.0, 1.3, 1.8), (0.01, 1.7, 2.2),
                                    [Quad((0.005, 1.3, 1.8), (0.0, 0.4, 0.0), (0.0, 0.0, 0.4), "lamp")]))
    room.lights.append(Light("wall", "lamp", (0.005, 1.5, 2.0), math.pi * 0.16 * 2850.0))
    # (1, 0, 0) x (0, 0, 1) = -y: the panel faces the floor.
    room.furniture.append(Furniture("ceiling_panels", (2.2, 2.69, 1.7), (2.8, 2.7, 2.3),
                                    [Quad((2.2, 2.695, 1.7), (0.6, 0.0, 0.0), (0.0, 0.0, 0.6), "panel")]))
    room.lights.append(Light("panel", "panel", (2.5, 2.695, 2.0), math.pi * 0.36 * 150.0))
    room.furniture.append(Furniture("cabinet", (3.9, 0.0, 0.2), (4.8, 1.6, 0.8),
                                    [Box((3.9, 0.0, 0.2), (4.8, 1.6, 0.8), "wood", faces="xXYzZ")]))
    return room


def wall_light_layout(room, caster: Caster, cfg: LayoutConfig = LayoutConfig()) -> ProbeLayout:
    """The fixed probes of :func:`wall_light_room`: A and B 0.8 m from the wall, 0.8 m either side
    of the light, C further into the room; cameras chosen as for any room."""
    probes = np.array([[0.8, 1.3, 1.2], [0.8, 1.3, 2.8], [2.3, 1.0, 2.0]])
    layout = ProbeLayout(probes, cfg.probe_radius, np.stack([probes[0], probes[1], 0.5 * (probes[0] + probes[1])]),
                         fov=cfg.camera_fov)
    cams = cameras_for(layout, caster, cfg)
    if cams is None:
        raise RoomlightError("wall light room: no clear camera for a probe")
    layout.cameras = cams
    return layout
