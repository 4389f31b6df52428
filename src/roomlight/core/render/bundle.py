"""Rendering an exported emitter bundle (``scene.xml``) with probe spheres and a camera."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import torch

from roomlight.errors import InputFileError, RoomlightError
from roomlight.core.render.materials import material
from roomlight.core.render.tensors import from_mitsuba_tensor
from roomlight.core.render.variant import mitsuba

__all__ = ["Probe", "parse_probe", "load_emitter_scene", "render_bundle"]


@dataclass(frozen=True)
class Probe:
    """A sphere placed in the scene: centre (metres, capture frame), radius, material name."""

    center: tuple[float, float, float]
    radius: float
    material: str = "mirror"

    def to_dict(self) -> dict:
        return {"type": "sphere", "center": list(self.center), "radius": float(self.radius),
                "bsdf": material(self.material)}


def parse_probe(text: str) -> Probe:
    """Parse ``x,y,z,r`` or ``x,y,z,r,material`` (material default ``mirror``)."""
    parts = [p.strip() for p in text.split(",")]
    try:
        if len(parts) not in (4, 5):
            raise ValueError
        x, y, z, r = (float(p) for p in parts[:4])
        if r <= 0:
            raise ValueError
    except ValueError:
        raise RoomlightError(f"probe {text!r}: expected x,y,z,radius[,material] with radius > 0") from None
    mat = parts[4] if len(parts) == 5 else "mirror"
    material(mat)  # validates the name
    return Probe((x, y, z), r, mat)


def load_emitter_scene(path) -> "object":
    """Load a bundle's ``scene.xml`` (path to the file or its directory) with ``mi.load_file``."""
    mi = mitsuba()
    p = Path(path)
    if p.is_dir():
        p = p / "scene.xml"
    if not p.is_file():
        raise InputFileError(p, "no such scene file", "pass a directory written by `roomlight emitter` or its scene.xml")
    try:
        return mi.load_file(str(p))
    except Exception as exc:  # Mitsuba reports parse errors as plain exceptions
        raise InputFileError(p, f"Mitsuba could not load the scene: {str(exc).splitlines()[0]}") from None


def render_bundle(path, sensor: dict, probes: list[Probe] = (), spp: int = 64, seed: int = 0,
                  max_depth: int = 4) -> torch.Tensor:
    """Render the bundle's emitter, plus ``probes``, from ``sensor``; returns (H, W, 3) linear RGB."""
    mi = mitsuba()
    base = load_emitter_scene(path)
    scene: dict = {"type": "scene", "integrator": {"type": "path", "max_depth": int(max_depth)},
                   "sensor": sensor}
    # Re-use the loaded emitter objects (mesh with its area light, or the env map) as they are.
    for i, shape in enumerate(base.shapes()):
        scene[f"shape_{i}"] = shape
    for i, em in enumerate(base.emitters()):
        if not mi.has_flag(em.flags(), mi.EmitterFlags.Surface):  # area lights come with their shape
            scene[f"emitter_{i}"] = em
    for i, probe in enumerate(probes):
        scene[f"probe_{i}"] = probe.to_dict()
    img = mi.render(mi.load_dict(scene), spp=spp, seed=seed)
    return from_mitsuba_tensor(img)[..., :3]
