"""``roomlight experiment capacity``: how well one 2.5D area light stands in for a whole 3-D room.

The supplementary's "Capacity of a single 2.5D area light", on the procedural rooms of
:mod:`roomlight.datagen.synth`. In each room (layout: :mod:`roomlight.evaluation.experiments.layout`):

1. the room's exact radiance and radial depth panoramas are path traced at three viewpoints
   (centre of probe A, centre of probe B, their midpoint), with the probes absent;
2. three probe spheres are rendered, one material at a time (gray diffuse, silver matte, silver
   mirror), each by its own close-up camera:

   - **ground truth**: in the full room, path traced, twice with different seeds (the two
     renders' difference is the *noise floor*);
   - lit only by an emitter built from each viewpoint's panorama, placed at that viewpoint:
     the **2.5D area light** (radiance on the depth mesh), the **environment map** (the same
     radiance at infinity) and a **sphere proxy** (the radiance on the smallest sphere around
     the viewpoint enclosing every probe, enlarged by 20 %, as the benchmark's baseline);
   - the 2.5D light at the midpoint once more with another seed (its own Monte Carlo noise);

3. linear RMSE over each probe's pixels (those where the probe is the first surface hit in the
   ground-truth scene, for every one of 4 x 4 sub-pixel rays).

Light paths: the panoramas are traced with ``max_depth`` bounces (synth's default 5) and every
probe render with ``max_depth + 1``, so light reaching a probe has bounced as often in the room
as the light the panorama recorded.

Units: every radiance is divided by the exposure factor of the room's midpoint panorama (its
log-average luminance becomes 1, the convention of the training data), so RMSEs are comparable
across rooms.

Layout of ``OUT``::

    OUT/capacity.json          settings, per-room records and the summary (see capacity_report)
    OUT/capacity.md            the tables; OUT/figures/*.png
    OUT/rooms/<room>/layout.json, pano-{A,B,M}.exr, renders.npz, result.json (written last)

``renders.npz`` (linear radiance in the calibrated units, float32): ``gt`` (M, 2, P, n, n, 3) two
ground-truth renders per material and probe; ``emit`` (M, K, V, P, n, n, 3) under each emitter kind
(:data:`~roomlight.evaluation.experiments.capacity_record.KINDS`) at each viewpoint (A, B, M); ``emit2``
(M, P, n, n, 3) the 2.5D light at the midpoint with another seed; ``masks`` (P, n, n) bool, the
scored pixels. ``pano-*.exr``: R, G, B (calibrated) + Z (metres), world-aligned (yaw 0).

A room with a ``result.json`` is skipped, so an interrupted run continues where it stopped.
"""

from __future__ import annotations

import json
import math
import os
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch

from roomlight.core.config import StrictConfig
from roomlight.errors import RoomlightError
from roomlight.evaluation.harness.records import check_settings
from roomlight.core.render.raycast import render_in_passes, shape_coverage
from roomlight.evaluation.experiments.capacity_record import KIND_LABELS, KINDS, RESULT, VIEW_TAGS, score_renders
from roomlight.evaluation.experiments.files import atomic_json, atomic_npz
from roomlight.evaluation.experiments.layout import Caster, LayoutConfig, ProbeLayout, place_layout, sphere_proxy_radius

__all__ = ["CapacityConfig", "run_capacity", "run_room", "room_name"]

_SALT = 0x43415041  # "CAPA": the placement's random stream, apart from the room generator's


@dataclass(frozen=True)
class CapacityConfig(StrictConfig):
    """Settings of the capacity experiment; the defaults are the paper's emitter resolution."""

    rooms: int = 10                   #: rooms measured (procedural seeds from ``seed``; unplaceable rooms are skipped)
    seed: int = 0                     #: first room seed; render seeds derive from it
    pano_height: int = 128            #: panorama / emitter height H (width 2H)
    pano_spp: int = 256               #: samples per pixel of the panoramas (a perfect square)
    image_size: int = 64              #: probe images are image_size x image_size pixels
    gt_spp: int = 1024                #: samples per pixel of each ground-truth probe render
    emitter_spp: int = 1024           #: samples per pixel of each render under an emitter
    max_depth: int = 5                #: bounces of the panorama paths (probe renders get one more)
    materials: tuple[str, ...] = ("diffuse", "matte", "mirror")  #: probe materials
    probe_radius: float = 0.12        #: probe sphere radius, metres
    sphere_margin: float = 0.2        #: sphere proxy radius = enclosing radius x (1 + this)
    supersample: int = 4              #: mask rays per pixel along each axis

    def __post_init__(self):
        for name in ("rooms", "pano_height", "pano_spp", "image_size", "gt_spp", "emitter_spp", "max_depth",
                     "supersample"):
            if getattr(self, name) < 1:
                raise RoomlightError(f"capacity: {name} must be >= 1, got {getattr(self, name)}")
        if math.isqrt(self.pano_spp) ** 2 != self.pano_spp:
            raise RoomlightError(f"capacity: pano_spp must be a perfect square (64, 144, 256...), got {self.pano_spp}")
        from roomlight.core.render.materials import MATERIALS

        bad = [m for m in self.materials if m not in MATERIALS]
        if bad or not self.materials:
            raise RoomlightError(f"capacity: unknown material(s) {', '.join(bad) or '(none)'}; "
                                 f"choose from {', '.join(MATERIALS)}")
        if not self.probe_radius > 0:
            raise RoomlightError(f"capacity: probe_radius must be > 0, got {self.probe_radius}")

    def layout_config(self) -> LayoutConfig:
        """The probe layout's settings that follow from these (probe size, sphere-proxy margin)."""
        return LayoutConfig(probe_radius=self.probe_radius, sphere_margin=self.sphere_margin)

    def scene_settings(self) -> dict:
        """The settings a room's numbers depend on (all but ``rooms``): finished rooms are reused
        only when these match."""
        d = self.to_dict()
        d.pop("rooms")
        return d


def room_name(seed) -> str:
    return seed if isinstance(seed, str) else f"room-{int(seed):06d}"


# --------------------------------------------------------------------------------------------
# Rendering pieces
# --------------------------------------------------------------------------------------------

def _probe_entries(layout: ProbeLayout, material: str) -> dict:
    from roomlight.core.render.materials import material as bsdf

    return {f"probe_{k}": {"type": "sphere", "center": [float(v) for v in p], "radius": float(layout.radius),
                           "bsdf": bsdf(material)} for k, p in enumerate(layout.probes)}


def _sensor(mi, origin, target, fov: float, width: int, height: int):
    from roomlight.core.render.camera import perspective_sensor

    return mi.load_dict(perspective_sensor(tuple(origin), tuple(target), fov_deg=fov, width=width, height=height))


def _render(mi, scene, sensor, spp: int, seed: int) -> np.ndarray:
    """(h, w, 3) float32 render of ``scene`` through ``sensor``, in averaged passes
    (:func:`~roomlight.core.render.raycast.render_in_passes`)."""
    size = sensor.film().crop_size()
    return render_in_passes(lambda n, sd: np.array(mi.render(scene, sensor=sensor, spp=n, seed=sd), np.float64)[..., :3],
                            spp, int(size[0]) * int(size[1]), seed).astype(np.float32)


def probe_masks(mi, scene, sensor, probe_ids, supersample: int = 4) -> np.ndarray:
    """(P, h, w) bool: pixels where every one of ``supersample``^2 sub-pixel rays hits probe k first.

    ``scene`` is the ground-truth scene (room + probes), so a probe hidden behind furniture or
    behind another probe loses those pixels.
    """
    size = sensor.film().crop_size()
    w, h, s = int(size[0]), int(size[1]), int(supersample)

    def rays(x, y):  # the sensor's film coordinates are [0, 1] across the frame
        pos = mi.Point2f(mi.Float((x / (w * s)).astype(np.float32)), mi.Float((y / (h * s)).astype(np.float32)))
        return sensor.sample_ray(0.0, 0.5, pos, mi.Point2f(0.5, 0.5))[0]

    shapes = {sh.id(): sh for sh in scene.shapes()}
    # every one of a pixel's rays on the probe: a mean of ones is exactly 1
    return shape_coverage(scene, rays, [shapes[pid] for pid in probe_ids], w, h, s) >= 1.0


class _Emitters:
    """The three emitter scenes of one material (probes in world coordinates), moved between
    viewpoints by rewriting the emitter's texture and vertices (offset by the viewpoint)."""

    def __init__(self, layout: ProbeLayout, material: str, resolution, max_depth: int):
        from roomlight.core.render.scene import EmitterScene

        integrator = {"type": "path", "max_depth": int(max_depth), "rr_depth": int(max_depth)}
        objs = _probe_entries(layout, material)
        # sphere:1 only sets the initial vertices; they are rewritten for every viewpoint
        self.scenes = {kind: EmitterScene("sphere:1" if kind == "sphere" else kind, resolution,
                                          objects=objs, integrator=integrator) for kind in KINDS}

    def place(self, kind: str, radiance: torch.Tensor, depth: torch.Tensor, origin, sphere_radius: float) -> None:
        from roomlight.core.emitter.area_light import area_light_vertices
        from roomlight.core.emitter.sphere import sphere_depth
        from roomlight.core.render.tensors import to_mitsuba_tensor

        es = self.scenes[kind]
        tex = to_mitsuba_tensor(es.texture_value(radiance))
        verts = None
        if kind != "envmap":
            d = depth if kind == "mesh" else sphere_depth(*radiance.shape[:2], sphere_radius)
            v = area_light_vertices(d.double()) + torch.as_tensor(np.asarray(origin), dtype=torch.float64)
            verts = es.mi.Float(v.float().reshape(-1).numpy())
        es.write_emitter_values(tex, verts)


# --------------------------------------------------------------------------------------------
# One room
# --------------------------------------------------------------------------------------------

def _seeds(cfg: CapacityConfig, index: int) -> dict:
    base = (cfg.seed * 1_000_003 + index * 7919) & 0x7FFFFFFF
    return {"pano": base, "gt0": base + 101, "gt1": base + 202, "emit": base + 303, "emit2": base + 404}


def run_room(room, out_dir, cfg: CapacityConfig, index: int = 0, layout: ProbeLayout | None = None,
             progress=None) -> dict:
    """Measure one room; writes ``out_dir`` (panoramas, renders, ``result.json``) and returns the record.

    Args:
        room: a :class:`roomlight.datagen.synth.spec.Room`.
        index: the room's position in the run (seeds the renders).
        layout: fixed probes and cameras; default: placed by :func:`place_layout` (seeded by the room).
        progress: optional callable receiving a short status string.
    Raises:
        RoomlightError: the room has no place for the probes.
    """
    from roomlight.core.io import write_panorama
    from roomlight.core.io.panorama import exposure_calibrate
    from roomlight.core.render.variant import mitsuba
    from roomlight.datagen.synth.camera import render_depth, render_radiance
    from roomlight.datagen.synth.scene import build_scene

    mi = mitsuba()
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    say = progress or (lambda _s: None)
    t0 = time.perf_counter()
    seeds = _seeds(cfg, index)
    room_scene = build_scene(room, max_depth=cfg.max_depth)
    if layout is None:
        rng = np.random.default_rng([int(getattr(room, "seed", 0)), _SALT, cfg.seed])
        layout = place_layout(room, Caster(room_scene), rng, cfg.layout_config())
    atomic_json(out / "layout.json", layout.to_dict())

    # 1. panoramas at the three viewpoints (probes absent), world-aligned (yaw 0)
    H = cfg.pano_height
    panos = []
    for v, tag in zip(layout.viewpoints, VIEW_TAGS):
        say(f"panorama {tag}")
        rad = np.clip(render_radiance(room_scene, tuple(v), height=H, spp=cfg.pano_spp, seed=seeds["pano"] + ord(tag)),
                      0.0, None)
        depth = render_depth(room_scene, tuple(v), height=H)
        if not np.isfinite(depth).all() or (depth <= 0).any():
            raise RoomlightError(f"{out.name}: a panorama ray from viewpoint {tag} escaped the room")
        panos.append((rad, depth))
    _, factor = exposure_calibrate(panos[2][0])  # the midpoint's log-average luminance becomes 1
    scale = 1.0 / factor
    for (rad, depth), tag in zip(panos, VIEW_TAGS):
        tmp = out / f".pano-{tag}.partial.exr"
        write_panorama(tmp, (rad * scale, depth), half=False,
                       metadata={"viewpoint": tag, "exposure_factor": factor, "spp": cfg.pano_spp})
        os.replace(tmp, out / f"pano-{tag}.exr")
    del room_scene

    n = cfg.image_size
    sensors = [_sensor(mi, o, t, layout.fov, n, n) for o, t in layout.cameras]
    P, V, M = len(layout.probes), len(layout.viewpoints), len(cfg.materials)
    gt = np.zeros((M, 2, P, n, n, 3), np.float32)
    emit = np.zeros((M, len(KINDS), V, P, n, n, 3), np.float32)
    emit2 = np.zeros((M, P, n, n, 3), np.float32)
    masks = None
    probe_ids = [f"probe_{k}" for k in range(P)]
    radii = [sphere_proxy_radius(layout.probes, layout.radius, v, cfg.sphere_margin) for v in layout.viewpoints]
    maps = [(torch.from_numpy(r * scale).float(), torch.from_numpy(d).float()) for r, d in panos]
    for mi_idx, material in enumerate(cfg.materials):
        # 2. ground truth: the room with the probes, one bounce more than the panoramas
        say(f"{material}: ground truth")
        gt_scene = build_scene(room, max_depth=cfg.max_depth + 1, extra=_probe_entries(layout, material))
        if masks is None:
            masks = np.stack([probe_masks(mi, gt_scene, s, probe_ids, cfg.supersample)[k]
                              for k, s in enumerate(sensors)])
            if (masks.sum(axis=(1, 2)) == 0).any():
                raise RoomlightError(f"{out.name}: a probe covers no whole pixel of its camera "
                                     "(raise --image-size)")
        for k, s in enumerate(sensors):
            for j, key in enumerate(("gt0", "gt1")):
                gt[mi_idx, j, k] = _render(mi, gt_scene, s, cfg.gt_spp, seeds[key] + 17 * k + 1000 * mi_idx) * scale
        del gt_scene
        # 3. the same probes lit by each emitter at each viewpoint
        em = _Emitters(layout, material, (H, 2 * H), cfg.max_depth + 1)
        for ki, kind in enumerate(KINDS):
            say(f"{material}: {KIND_LABELS[kind]}")
            for vi, v in enumerate(layout.viewpoints):
                em.place(kind, maps[vi][0], maps[vi][1], v, radii[vi])
                scene = em.scenes[kind].scene
                for k, s in enumerate(sensors):
                    emit[mi_idx, ki, vi, k] = _render(mi, scene, s, cfg.emitter_spp,
                                                      seeds["emit"] + 17 * k + 1000 * mi_idx)
                if kind == "mesh" and vi == 2:
                    for k, s in enumerate(sensors):
                        emit2[mi_idx, k] = _render(mi, scene, s, cfg.emitter_spp,
                                                   seeds["emit2"] + 17 * k + 1000 * mi_idx)
        del em

    record = score_renders(gt, emit, emit2, masks, cfg.materials)
    record.update({"name": out.name, "seed": getattr(room, "seed", None), "room": _summary(room), "plan": _plan(room),
                   "exposure_factor": factor, "layout": layout.to_dict(), "sphere_radii": radii,
                   "mask_pixels": masks.sum(axis=(1, 2)).tolist(), "seconds": round(time.perf_counter() - t0, 2),
                   "settings": cfg.scene_settings()})
    atomic_npz(out / "renders.npz", gt=gt, emit=emit, emit2=emit2, masks=masks)
    atomic_json(out / RESULT, record)
    return record


def _plan(room) -> dict:
    """Top-view footprints for the figures: floor cells (x0, z0, x1, z1); per piece of furniture
    the box around its parts (x0, z0, x1, z1, kind, False), or for a light fixture one box per
    emitting part (x0, z0, x1, z1, kind, True); windows as wall segments (x0, z0, x1, z1)."""
    from roomlight.datagen.synth.layout import part_bounds

    emitting = set(room.emitters())
    boxes = []
    for f in room.furniture:
        if not f.parts:
            continue
        bounds = [part_bounds(p) for p in f.parts]
        lights = [p.material in emitting for p in f.parts]
        if not any(lights):
            lo = np.min([b[0] for b in bounds], axis=0)
            hi = np.max([b[1] for b in bounds], axis=0)
            boxes.append([float(lo[0]), float(lo[2]), float(hi[0]), float(hi[2]), str(f.kind), False])
        for p, (plo, phi) in zip(f.parts, bounds):
            if p.material in emitting:
                boxes.append([float(plo[0]), float(plo[2]), float(phi[0]), float(phi[2]), str(f.kind), True])
    windows = [[float(w.origin[0]), float(w.origin[2]), float(w.origin[0] + w.edge_a[0]),
                float(w.origin[2] + w.edge_a[2])] for w in room.windows]
    return {"cells": [[float(v) for v in c] for c in room.cells], "furniture": boxes, "windows": windows}


def _summary(room) -> dict:
    return {"room_type": getattr(room, "room_type", None), "lighting": getattr(room, "lighting", None),
            "shell": getattr(room, "shell", None), "height": getattr(room, "height", None),
            "lights_on": sum(1 for lt in getattr(room, "lights", []) if getattr(lt, "on", True)),
            "windows": len(getattr(room, "windows", []))}


# --------------------------------------------------------------------------------------------
# The run
# --------------------------------------------------------------------------------------------

def _check_settings(out: Path, cfg: CapacityConfig) -> None:
    check_settings(out / "settings.json", cfg.scene_settings())


def run_capacity(out_dir, cfg: CapacityConfig = CapacityConfig(), rooms=None, progress: bool = True,
                 max_seeds: int | None = None) -> dict:
    """Measure ``cfg.rooms`` rooms (resumable) and write the report; returns the summary dict.

    Args:
        rooms: ``[(name, Room, ProbeLayout or None)]`` to measure instead of procedural rooms
            (tests, hand-made rooms); default: ``generate_room(seed)`` for seeds from ``cfg.seed``,
            rooms without a valid placement skipped, until ``cfg.rooms`` are measured.
        max_seeds: give up after this many seeds (default: 4 x rooms + 10).
    """
    from roomlight.evaluation.experiments.capacity_report import write_capacity_report
    from roomlight.core.progress import progress_bar

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    _check_settings(out, cfg)
    t0 = time.perf_counter()
    records, skipped = [], {}
    target = len(rooms) if rooms is not None else cfg.rooms
    bar = progress_bar(total=target, desc="capacity", unit="room", disable=not progress)
    done_before = 0

    def attempt(index, name, make):
        nonlocal done_before
        rdir = out / "rooms" / name
        if (rdir / RESULT).is_file():
            rec = json.loads((rdir / RESULT).read_text())
            done_before += 1
        elif (rdir / "skipped.json").is_file():
            skipped[name] = json.loads((rdir / "skipped.json").read_text())["reason"]
            return
        else:
            room, layout = make()
            try:
                rec = run_room(room, rdir, cfg, index, layout, progress=lambda s: bar.set_postfix_str(f"{name}: {s}"))
            except RoomlightError as exc:
                if layout is not None:
                    raise
                skipped[name] = str(exc)
                rdir.mkdir(parents=True, exist_ok=True)
                atomic_json(rdir / "skipped.json", {"reason": str(exc)})
                return
        records.append(rec)
        bar.update()

    if rooms is not None:
        for i, (name, room, layout) in enumerate(rooms):
            attempt(i, name, lambda room=room, layout=layout: (room, layout))
    else:
        from roomlight.datagen.synth.rooms import generate_room

        limit = max_seeds if max_seeds is not None else 4 * cfg.rooms + 10
        seed = cfg.seed
        while len(records) < cfg.rooms and seed < cfg.seed + limit:
            attempt(seed - cfg.seed, room_name(seed), lambda s=seed: (generate_room(s), None))
            seed += 1
    bar.close()
    if not records:
        raise RoomlightError(f"capacity: no room could be measured ({len(skipped)} skipped: "
                             f"{next(iter(skipped.values()), '')})")
    wall = time.perf_counter() - t0
    return write_capacity_report(out, records, cfg, skipped=skipped, wall_seconds=wall,
                                 resumed_rooms=done_before)
