"""Staging a photograph in a procedural room: the camera, the inserted objects, the probes.

Every decision is a ray cast against the room's Mitsuba scene (``scene.ray_intersect``), so it
holds for any room the generator makes:

1. **Eye.** The camera stands at the room's capture point (which the generator keeps at least
   0.4 m from every surface), raised to an eye height drawn in ``eye_height``; a height whose
   26 test rays find a surface closer than 0.25 m is lowered to the capture point's own height.
2. **Target.** Rays from the eye over a ring of headings and 15-55 degrees downwards find the
   horizontal, upward-facing surfaces 1-4 m away (horizontally) and below 1.3 m: furniture tops
   (above 10 cm) or the floor. A furniture top is chosen when one is seen (a floor point with
   probability 0.15, or when none is); the camera looks at it, jittered by up to 15 cm.
3. **Supports.** Camera rays through a grid over the frame (a 10 % border left out) find the
   visible horizontal surfaces: candidate resting points.
4. **Objects.** Each object (shape, material, size in proportion to its distance to the camera)
   goes on a resting point drawn near the target (Gaussian weight, sigma 0.6 m) whose **free
   column** holds it: rays cast down over its footprint (plus 2 cm) from just above its top all
   land on the same flat surface, and rays cast up from that surface meet nothing within its
   height. Footprints keep 3 cm apart.
5. **Probes.** Spheres rest the same way next to the objects (weight by the distance to the
   nearest object, sigma 0.4 m), 2 mm above their support.
6. **Checks.** Every object must show ``min_pixels`` whole pixels in the photo and touch no image
   border; every probe must be unoccluded (its coverage with the room and the objects at least
   98 % of its coverage alone), inside the frame and show ``min_pixels`` whole pixels. A failed
   check restarts from step 2 with another target; a room that fails too often is replaced.

The **oracle centre** (where the oracle light is captured) is the first of the probes' centroid,
then points 0.2, 0.4, ... 1 m above it, then the same above each probe centre, that lies in free
space (no surface within 5 cm) and sees every probe whole (a ray towards each probe centre meets
nothing before the probe's far side), so every probe lies inside the captured 2.5D light. When
none sees them all, the one that sees the most.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from roomlight.errors import RoomlightError
from roomlight.fitting.photo.camera import PhotoCamera
from roomlight.evaluation.photobench.config import PhotoBenchConfig
from roomlight.evaluation.photobench.objects import OBJECT_SHAPES, InsertedObject, ProbeSphere, draw_material
from roomlight.evaluation.photobench.tracing import trace_coverage
from roomlight.core.render.raycast import RayCaster, sphere_directions
from roomlight.core.render.variant import mitsuba

__all__ = ["StagingError", "Staging", "RayCaster", "palette", "eye_position", "choose_target", "support_points",
           "free_column", "stage_photo", "sphere_directions", "TRIES_PER_ROOM"]

#: Targets tried in one room before the room is given up.
TRIES_PER_ROOM = 12
_UP = np.array([0.0, 1.0, 0.0])
_GAP = 0.002            # objects and probes hover this far above their support (no coincident faces)
_CLEAR = 0.02           # free margin around a footprint
_SPACING = 0.03         # gap between footprints
#: Heights (m) above the probes' centroid (then above each probe) tried for the oracle centre.
_ORACLE_LIFTS = (0.0, 0.2, 0.4, 0.6, 0.8, 1.0)


class StagingError(RoomlightError):
    """No photograph could be staged in a room (no visible support, objects hidden, ...)."""


@dataclass
class Staging:
    """A staged photograph (all positions in metres, world frame)."""

    camera: PhotoCamera
    target: np.ndarray
    objects: list[InsertedObject]
    probes: list[ProbeSphere]
    oracle_center: np.ndarray
    tries: int


def _clearance(caster: RayCaster, point) -> tuple[float, int]:
    """(nearest hit distance, back-face hits) over 26 rays from ``point``."""
    d = sphere_directions(26)
    t, n, _ = caster.cast(np.asarray(point, np.float64)[None], d)
    back = int(np.sum(np.isfinite(t) & ((n * d).sum(1) > 0)))
    return float(np.min(t)), back


def eye_position(room, caster: RayCaster, rng: np.random.Generator, eye_height) -> np.ndarray:
    """The camera position (step 1 of the module docstring)."""
    c = np.asarray(room.capture, np.float64)
    y = float(rng.uniform(*eye_height))
    eye = np.array([c[0], min(y, room.height - 0.25), c[2]])
    near, back = _clearance(caster, eye)
    if near < 0.25 or back:
        eye = c.copy()
    return eye


def choose_target(caster: RayCaster, eye: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """A look-at point on a horizontal surface (step 2 of the module docstring)."""
    yaws = rng.uniform(0, 2 * math.pi) + np.linspace(0, 2 * math.pi, 72, endpoint=False)
    pitches = np.radians(np.linspace(-15, -55, 9))
    yy, pp = np.meshgrid(yaws, pitches)
    d = np.stack([np.cos(pp) * np.sin(yy), np.sin(pp), -np.cos(pp) * np.cos(yy)], -1).reshape(-1, 3)
    t, n, p = caster.cast(eye[None], d)
    horiz = np.hypot(p[:, 0] - eye[0], p[:, 2] - eye[2])
    ok = np.isfinite(t) & (n[:, 1] > 0.95) & (horiz > 1.0) & (horiz < 4.0) & (p[:, 1] < 1.3)
    if not ok.any():
        raise StagingError("no horizontal surface 1-4 m from the camera")
    tops = ok & (p[:, 1] > 0.1)
    pool = np.nonzero(tops if tops.any() and rng.uniform() > 0.15 else ok)[0]
    q = p[pool[int(rng.integers(len(pool)))]].copy()
    q[[0, 2]] += rng.uniform(-0.15, 0.15, 2)
    return q


def support_points(caster: RayCaster, camera: PhotoCamera, rows: int = 36, border: float = 0.1) -> np.ndarray:
    """(M, 3) visible points on horizontal upward-facing surfaces (step 3), 0.5-6 m from the camera."""
    cols = max(8, round(rows * camera.width / camera.height))
    xs = camera.width * (border + (1 - 2 * border) * (np.arange(cols) + 0.5) / cols)
    ys = camera.height * (border + (1 - 2 * border) * (np.arange(rows) + 0.5) / rows)
    xx, yy = np.meshgrid(xs, ys)
    d = camera.directions(xx.ravel(), yy.ravel())
    t, n, p = caster.cast(camera.origin[None], d)
    ok = np.isfinite(t) & (n[:, 1] > 0.95) & ((n * d).sum(1) < 0) & (t > 0.5) & (t < 6.0)
    return p[ok]


def _disk(center_xz, radius: float) -> np.ndarray:
    """(N, 2) points covering a disk: the centre and three rings."""
    pts = [np.zeros(2)]
    for k, frac in enumerate((1 / 3, 2 / 3, 1.0)):
        m = 8 * (k + 1)
        a = 2 * math.pi * np.arange(m) / m
        pts.append(frac * radius * np.stack([np.cos(a), np.sin(a)], -1))
    return np.concatenate([p.reshape(-1, 2) for p in pts]) + np.asarray(center_xz, np.float64)


def free_column(caster: RayCaster, center_xz, support_y: float, radius: float, height: float) -> bool:
    """Whether an object of footprint ``radius`` and ``height`` can rest at ``center_xz`` on a
    surface at ``support_y`` (step 4 of the module docstring)."""
    xz = _disk(center_xz, radius + _CLEAR)
    top = support_y + height + 0.03
    down = np.stack([xz[:, 0], np.full(len(xz), top), xz[:, 1]], -1)
    t, n, _ = caster.cast(down, np.tile(-_UP, (len(xz), 1)))
    if not (np.all(np.abs(t - (top - support_y)) < 0.004) and np.all(n[:, 1] > 0.95)):
        return False
    up = np.stack([xz[:, 0], np.full(len(xz), support_y + 0.003), xz[:, 1]], -1)
    t, _, _ = caster.cast(up, np.tile(_UP, (len(xz), 1)))
    return bool(np.all(t > height + 0.03))


def _weights(points: np.ndarray, anchors: np.ndarray, sigma: float) -> np.ndarray:
    d = np.min(np.linalg.norm(points[:, None, :] - anchors[None], axis=-1), axis=1)
    w = np.exp(-0.5 * (d / sigma) ** 2) + 1e-12
    return w / w.sum()


def _place_objects(caster, camera, supports, target, rng, config: PhotoBenchConfig) -> list[InsertedObject]:
    count = int(rng.integers(config.objects[0], config.objects[1] + 1))
    weights = _weights(supports, target[None], 0.6)
    placed: list[InsertedObject] = []
    footprints: list[tuple[np.ndarray, float]] = []
    for _ in range(40 * count):
        if len(placed) == count:
            break
        p = supports[int(rng.choice(len(supports), p=weights))]
        shape = str(rng.choice(OBJECT_SHAPES))
        dist = float(np.linalg.norm(p - camera.origin))
        radius = float(np.clip(rng.uniform(*config.object_size) * dist, 0.04, 0.3))
        if shape == "box":
            aspect = rng.uniform(0.5, 1.3, 3)
            size = tuple(float(s) for s in aspect * (2 * radius / np.linalg.norm(aspect)))
        else:
            size = (radius,)
        k = len(placed) + 1
        obj = InsertedObject(f"obj{k}", k, shape, size, float(rng.uniform(0, 360)), (0.0, 0.0, 0.0),
                             draw_material(rng, config.metal_fraction, config.roughness, palette(config), config.metal_colours))
        v, _ = obj.local_geometry()
        rho = float(np.max(np.hypot(v[:, 0], v[:, 2])))
        h = float(v[:, 1].max() - v[:, 1].min())
        xz = p[[0, 2]]
        if any(np.linalg.norm(xz - c) < rho + r + _SPACING for c, r in footprints):
            continue
        if not free_column(caster, xz, float(p[1]), rho, h):
            continue
        translate = (float(p[0]), float(p[1] - v[:, 1].min() + _GAP), float(p[2]))
        placed.append(InsertedObject(obj.id, obj.label, shape, size, obj.yaw, translate, obj.material))
        footprints.append((xz, rho))
    if len(placed) < count:
        raise StagingError(f"found room for {len(placed)} of {count} objects near the target")
    return placed


def _place_probes(caster, camera, supports, objects, rng, config: PhotoBenchConfig) -> list[ProbeSphere]:
    anchors = np.array([o.translate for o in objects])
    weights = _weights(supports, anchors, 0.4)
    footprints = []
    for o in objects:
        v, _ = o.local_geometry()
        footprints.append((np.asarray(o.translate)[[0, 2]], float(np.max(np.hypot(v[:, 0], v[:, 2])))))
    probes: list[ProbeSphere] = []
    for _ in range(40 * config.probes):
        if len(probes) == config.probes:
            break
        p = supports[int(rng.choice(len(supports), p=weights))]
        dist = float(np.linalg.norm(p - camera.origin))
        r = float(np.clip(config.probe_size * dist, 0.03, 0.2))
        xz = p[[0, 2]]
        if any(np.linalg.norm(xz - c) < rr + r + _SPACING for c, rr in footprints):
            continue
        if not free_column(caster, xz, float(p[1]), r, 2 * r):
            continue
        k = len(probes) + 1
        probes.append(ProbeSphere(f"probe{k}", k, (float(p[0]), float(p[1] + r + _GAP), float(p[2])), r))
        footprints.append((xz, r))
    if len(probes) < config.probes:
        raise StagingError(f"found room for {len(probes)} of {config.probes} probes near the objects")
    return probes


def _check_objects(room_scene_with_objects, meshes, camera: PhotoCamera, config: PhotoBenchConfig) -> None:
    cov = trace_coverage(room_scene_with_objects, camera, meshes, config.supersample)
    for k, c in enumerate(cov):
        whole = int((c >= 1.0 - 1e-6).sum())
        border = c[0].any() or c[-1].any() or c[:, 0].any() or c[:, -1].any()
        if whole < config.min_pixels or border:
            raise StagingError(f"object {k + 1} shows {whole} whole pixels"
                               + (" and touches the image border" if border else ""))


def _check_probes(scene_all, probe_shapes, camera: PhotoCamera, config: PhotoBenchConfig) -> None:
    mi = mitsuba()
    alone = mi.load_dict({"type": "scene", **{f"p{k}": s for k, s in enumerate(probe_shapes)}})
    free = trace_coverage(alone, camera, probe_shapes, config.supersample)
    seen = trace_coverage(scene_all, camera, probe_shapes, config.supersample)
    for k, (f, s) in enumerate(zip(free, seen)):
        border = f[0].any() or f[-1].any() or f[:, 0].any() or f[:, -1].any()
        whole = int((s >= 1.0 - 1e-6).sum())
        if border or s.sum() < 0.98 * f.sum() or whole < config.min_pixels:
            raise StagingError(f"probe {k + 1} is occluded, cut by the frame or too small ({whole} whole pixels)")


def _oracle_center(caster: RayCaster, probes: list[ProbeSphere]) -> np.ndarray:
    """The oracle light's capture point (see the module docstring)."""
    centres = np.array([p.center for p in probes])
    radii = np.array([p.radius for p in probes])
    mean = centres.mean(0)
    candidates = [mean + [0.0, h, 0.0] for h in _ORACLE_LIFTS] + [c + [0.0, h, 0.0] for h in _ORACLE_LIFTS
                                                                  for c in centres]
    best, best_seen = centres[int(np.argmin(np.linalg.norm(centres - mean, axis=1)))], -1
    for c in candidates:
        near, back = _clearance(caster, c)
        # free space: no surface within 5 cm, and not inside a solid (rays from inside a closed
        # solid meet its faces from behind); the probes' own spheres are not in this scene
        if near < 0.05 or back:
            continue
        to = centres - c
        dist = np.linalg.norm(to, axis=1)
        t, _, _ = caster.cast(c[None], to / np.maximum(dist, 1e-9)[:, None])
        seen = int(np.sum(t > dist + radii))
        if seen == len(probes):
            return c
        if seen > best_seen:
            best, best_seen = c, seen
    return best


def palette(config: PhotoBenchConfig) -> str:
    """The objects' colour palette of a suite (:func:`~roomlight.evaluation.photobench.objects.draw_material`)."""
    return "wide" if config.suite == "wide" else "hsv"


def stage_photo(scenes, rng: np.random.Generator, config: PhotoBenchConfig, fov: float | None = None) -> Staging:
    """Stage one photograph in a room (see the module docstring); raises :class:`StagingError`.

    Args:
        scenes: the room's :class:`~roomlight.evaluation.photobench.roomscene.RoomScenes` (or a set with
            its interface, :class:`~roomlight.evaluation.photobench.captured.CapturedSet`).
        fov: the photo's horizontal field of view (default ``config.fov``). With ``config.pitch_range``
            each attempt draws a pitch and aims the camera at the target's vertical with it.
    """
    from roomlight.evaluation.photobench.variety import aim_at_pitch

    room = scenes.room
    caster = RayCaster(scenes.base)
    eye = eye_position(room, caster, rng, config.eye_height)
    last = "no attempt"
    for attempt in range(1, TRIES_PER_ROOM + 1):
        try:
            target = choose_target(caster, eye, rng)
            look = target if config.pitch_range is None else aim_at_pitch(eye, target, rng.uniform(*config.pitch_range))
            camera = PhotoCamera.look_at(eye, look, fov or config.fov, config.width, config.height)
            supports = support_points(caster, camera)
            if len(supports) < 8:
                raise StagingError("too few visible horizontal surfaces")
            objects = _place_objects(caster, camera, supports, target, rng, config)
            probes = _place_probes(caster, camera, supports, objects, rng, config)
            meshes = [o.mitsuba_mesh() for o in objects]
            scene_obj = scenes.scene({o.id: m for o, m in zip(objects, meshes)})
            _check_objects(scene_obj, meshes, camera, config)
            shapes = [p.mitsuba_shape("diffuse") for p in probes]
            scene_all = scenes.scene({**{o.id: m for o, m in zip(objects, meshes)},
                                      **{p.id: s for p, s in zip(probes, shapes)}})
            _check_probes(scene_all, shapes, camera, config)
            centre = _oracle_center(RayCaster(scene_obj), probes)
            return Staging(camera, target, objects, probes, centre, attempt)
        except StagingError as exc:
            last = str(exc)
    raise StagingError(f"room {room.seed}: no photograph after {TRIES_PER_ROOM} targets (last: {last})")
