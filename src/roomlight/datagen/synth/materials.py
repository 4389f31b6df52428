"""Room material palettes (realistic albedo ranges) and their Mitsuba BSDF dicts.

Albedo ranges follow common measurements of interior finishes: white paint 0.6-0.85, pastel
paint 0.3-0.75, wood floors 0.08-0.45, tiles 0.05-0.75, carpet 0.05-0.4, fabrics 0.03-0.6.
Colours are drawn in sRGB-encoded HSV and linearised (:func:`roomlight.datagen.synth.color.hsv_albedo`).
"""

from __future__ import annotations

import numpy as np

from roomlight.datagen.synth.color import hsv_albedo
from roomlight.datagen.synth.spec import Material
from roomlight.datagen.synth.textures import make_texture

__all__ = ["BOOK_MATERIALS", "CANVAS_MATERIALS", "bsdf_dict", "concrete_floor", "emission_texture", "room_palette"]

BOOK_MATERIALS = tuple(f"book_{i}" for i in range(5))
CANVAS_MATERIALS = tuple(f"canvas_{i}" for i in range(3))


def _seed(rng) -> int:
    return int(rng.integers(0, 2**31 - 1))


def _paint(rng, name: str) -> Material:
    u = rng.random()
    if u < 0.55:
        alb = hsv_albedo(rng.random(), rng.uniform(0.0, 0.08), rng.uniform(0.82, 0.95))
    elif u < 0.9:
        alb = hsv_albedo(rng.random(), rng.uniform(0.1, 0.35), rng.uniform(0.6, 0.92))
    else:
        alb = hsv_albedo(rng.random(), rng.uniform(0.05, 0.5), rng.uniform(0.3, 0.55))
    tex = None
    v = rng.random()
    if v < 0.25:
        tex = {"pattern": "noise", "seed": _seed(rng), "amplitude": float(rng.uniform(0.04, 0.12)),
               "tile": float(rng.uniform(1.0, 2.5))}
    elif v < 0.35:
        second = tuple(float(c) * rng.uniform(0.7, 0.9) for c in alb)
        tex = {"pattern": "stripes", "seed": _seed(rng), "count": int(rng.integers(4, 12)),
               "second": second, "tile": float(rng.uniform(0.6, 1.5))}
    return Material(name, "diffuse", alb, texture=tex)


def _floor(rng, name: str) -> Material:
    u = rng.random()
    if u < 0.45:
        alb = hsv_albedo(rng.uniform(0.05, 0.1), rng.uniform(0.35, 0.7), rng.uniform(0.35, 0.75))
        tex = {"pattern": "wood", "seed": _seed(rng), "planks": int(rng.integers(4, 9)),
               "segments": int(rng.integers(1, 3)), "tile": float(rng.uniform(0.8, 1.6))}
        return Material(name, "plastic", alb, float(rng.uniform(0.08, 0.35)), tex)
    if u < 0.7:
        dark = rng.random() < 0.3
        alb = hsv_albedo(rng.random(), rng.uniform(0.0, 0.2), rng.uniform(0.15, 0.35) if dark else rng.uniform(0.6, 0.9))
        count = int(rng.integers(2, 5))
        second = hsv_albedo(rng.random(), 0.05, 0.2) if rng.random() < 0.15 else None
        tex = {"pattern": "tiles", "seed": _seed(rng), "count": count, "second": second,
               "grout": hsv_albedo(0.1, 0.05, rng.uniform(0.4, 0.8)), "tile": count * float(rng.uniform(0.3, 0.6))}
        return Material(name, "plastic", alb, float(rng.uniform(0.04, 0.2)), tex)
    if u < 0.9:
        alb = hsv_albedo(rng.random(), rng.uniform(0.05, 0.5), rng.uniform(0.25, 0.65))
        tex = {"pattern": "noise", "seed": _seed(rng), "amplitude": float(rng.uniform(0.1, 0.25)),
               "beta": 1.0, "tile": float(rng.uniform(0.3, 0.6))}
        return Material(name, "diffuse", alb, texture=tex)
    alb = hsv_albedo(0.1, rng.uniform(0.0, 0.08), rng.uniform(0.4, 0.65))
    tex = {"pattern": "noise", "seed": _seed(rng), "amplitude": float(rng.uniform(0.08, 0.2)), "tile": 2.0}
    return Material(name, "plastic", alb, float(rng.uniform(0.2, 0.45)), tex)


def concrete_floor(rng, name: str) -> Material:
    """Concrete, epoxy or polished stone: grey to beige, 0.2-0.55 albedo, mottled, from matte
    (alpha 0.5) to polished (0.05)."""
    alb = hsv_albedo(rng.uniform(0.05, 0.15), rng.uniform(0.0, 0.15), rng.uniform(0.35, 0.75))
    tex = {"pattern": "noise", "seed": _seed(rng), "amplitude": float(rng.uniform(0.1, 0.3)),
           "beta": float(rng.uniform(1.0, 2.0)), "tile": float(rng.uniform(1.5, 4.0))}
    return Material(name, "plastic", alb, float(rng.uniform(0.05, 0.5)), tex)


def _wood(rng, name: str, tile: float = 0.8) -> Material:
    alb = hsv_albedo(rng.uniform(0.05, 0.11), rng.uniform(0.3, 0.7), rng.uniform(0.25, 0.8))
    tex = {"pattern": "wood", "seed": _seed(rng), "planks": 8, "segments": 1, "tile": tile}
    return Material(name, "plastic", alb, float(rng.uniform(0.1, 0.4)), tex)


def _color(rng, name: str, s=(0.2, 0.7), v=(0.2, 0.8), bsdf: str = "diffuse", texture: bool = False) -> Material:
    alb = hsv_albedo(rng.random(), rng.uniform(*s), rng.uniform(*v))
    tex = None
    if texture:
        tex = {"pattern": "noise", "seed": _seed(rng), "amplitude": 0.15, "beta": 1.0, "tile": 0.3}
    return Material(name, bsdf, alb, float(rng.uniform(0.1, 0.35)), tex)


def room_palette(rng: np.random.Generator) -> dict[str, Material]:
    """All non-emissive materials a room may use, keyed by name (see the module docstring)."""
    m: dict[str, Material] = {}
    m["wall"] = _paint(rng, "wall")
    m["ceiling"] = Material("ceiling", "diffuse", hsv_albedo(rng.random(), rng.uniform(0, 0.04), rng.uniform(0.88, 0.96)))
    m["floor"] = _floor(rng, "floor")
    m["frame"] = (Material("frame", "plastic", hsv_albedo(0, 0, rng.uniform(0.85, 0.95)), 0.2)
                  if rng.random() < 0.6 else
                  Material("frame", "plastic", hsv_albedo(0, 0, rng.uniform(0.1, 0.35)), 0.25))
    m["door"] = _wood(rng, "door", 1.0) if rng.random() < 0.5 else Material(
        "door", "plastic", hsv_albedo(rng.random(), rng.uniform(0, 0.3), rng.uniform(0.5, 0.95)), 0.25)
    m["metal"] = Material("metal", "metal", hsv_albedo(0.1, rng.uniform(0, 0.3), rng.uniform(0.7, 0.95)),
                          float(rng.uniform(0.1, 0.4)))
    m["adj_wall"] = _paint(rng, "adj_wall")
    m["adj_floor"] = _floor(rng, "adj_floor")
    m["adj_ceiling"] = Material("adj_ceiling", "diffuse", hsv_albedo(0, 0, rng.uniform(0.8, 0.92)))
    m["wood"] = _wood(rng, "wood")
    m["painted"] = _color(rng, "painted", (0.0, 0.5), (0.3, 0.95), "plastic")
    m["fabric"] = _color(rng, "fabric", (0.1, 0.7), (0.15, 0.75), texture=True)
    m["fabric2"] = _color(rng, "fabric2", (0.1, 0.7), (0.2, 0.85), texture=True)
    m["black"] = Material("black", "plastic", hsv_albedo(0, 0, rng.uniform(0.03, 0.08)), 0.1)
    m["white"] = Material("white", "diffuse", hsv_albedo(0, 0, rng.uniform(0.8, 0.92)))
    m["leaf"] = Material("leaf", "diffuse", hsv_albedo(rng.uniform(0.22, 0.38), rng.uniform(0.4, 0.8), rng.uniform(0.2, 0.45)),
                         texture={"pattern": "noise", "seed": _seed(rng), "amplitude": 0.35, "beta": 1.0, "tile": 0.2})
    m["pot"] = _color(rng, "pot", (0.0, 0.6), (0.2, 0.8), "plastic")
    m["rug"] = Material("rug", "diffuse", hsv_albedo(rng.random(), 0.3, 0.6),
                        texture={"pattern": "canvas" if rng.random() < 0.5 else "stripes", "seed": _seed(rng),
                                 "colors": 3, "count": int(rng.integers(3, 9)), "tile": float(rng.uniform(0.8, 2.0)),
                                 "second": hsv_albedo(rng.random(), 0.5, 0.4)})
    for name in BOOK_MATERIALS:
        m[name] = _color(rng, name, (0.1, 0.8), (0.1, 0.85))
    for name in CANVAS_MATERIALS:
        m[name] = Material(name, "diffuse", (1.0, 1.0, 1.0),
                           texture={"pattern": "canvas", "seed": _seed(rng), "colors": int(rng.integers(2, 5)), "tile": 1.0})
    return m


def _bitmap(mi, data: np.ndarray) -> dict:
    return {"type": "bitmap", "data": mi.TensorXf(np.ascontiguousarray(data, np.float32)), "raw": True,
            "filter_type": "bilinear", "wrap_mode": "repeat"}


def _rgb(v) -> dict:
    return {"type": "rgb", "value": [float(c) for c in v]}


def bsdf_dict(mi, m: Material) -> dict:
    """Mitsuba BSDF dict for a material (emissive materials get a black diffuse BSDF)."""
    if m.emission is not None or m.bsdf == "black":
        return {"type": "diffuse", "reflectance": _rgb((0.0, 0.0, 0.0))}
    refl = _bitmap(mi, make_texture(m.texture, m.albedo)) if m.texture else _rgb(m.albedo)
    if m.bsdf == "diffuse":
        return {"type": "diffuse", "reflectance": refl}
    if m.bsdf == "plastic":
        return {"type": "roughplastic", "distribution": "ggx", "alpha": float(m.roughness),
                "int_ior": 1.5, "diffuse_reflectance": refl}
    if m.bsdf == "metal":
        return {"type": "roughconductor", "distribution": "ggx", "alpha": float(m.roughness),
                "material": "none", "specular_reflectance": refl}
    raise ValueError(f"bsdf_dict: unknown bsdf kind {m.bsdf!r} of material {m.name!r}")


def emission_texture(mi, m: Material) -> dict:
    """Mitsuba texture dict of an emissive material's radiance."""
    if m.emission_texture:
        return _bitmap(mi, make_texture(m.emission_texture) * np.asarray(m.emission, np.float32))
    return _rgb(m.emission)
