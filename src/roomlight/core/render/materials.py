"""Named materials for probes and benchmark objects (Mitsuba BSDF dicts).

The paper's three benchmark materials are ``diffuse`` (gray diffuse), ``matte`` (silver,
rough conductor) and ``mirror`` (silver, smooth conductor); ``glossy`` is a plastic for
figures, ``white`` the albedo-1 Lambertian used by furnace tests.
"""

from __future__ import annotations

from roomlight.errors import RoomlightError

__all__ = ["MATERIALS", "material", "principled_bsdf"]

MATERIALS: dict[str, dict] = {
    "diffuse": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.5, 0.5, 0.5]}},
    "white": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [1.0, 1.0, 1.0]}},
    "matte": {"type": "roughconductor", "material": "Ag", "distribution": "ggx", "alpha": 0.2},
    "mirror": {"type": "conductor", "material": "Ag"},
    "glossy": {"type": "roughplastic", "distribution": "ggx", "alpha": 0.08,
               "diffuse_reflectance": {"type": "rgb", "value": [0.15, 0.15, 0.15]}},
}


def material(name: str) -> dict:
    """A fresh copy of the named material's BSDF dict."""
    import copy

    if name not in MATERIALS:
        raise RoomlightError(f"unknown material {name!r}; choose one of {', '.join(MATERIALS)}")
    return copy.deepcopy(MATERIALS[name])


def principled_bsdf(base_color, roughness: float, metallic: float) -> dict:
    """A Mitsuba ``principled`` BSDF dict (its other parameters at Mitsuba's defaults): the
    material of inserted objects and of objects whose material is fitted."""
    return {"type": "principled", "base_color": {"type": "rgb", "value": [float(c) for c in base_color]},
            "roughness": float(roughness), "metallic": float(metallic)}
