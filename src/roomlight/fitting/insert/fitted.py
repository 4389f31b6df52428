"""A finished ``fit-photo`` output folder read back: the photograph, its camera, the fitted light and
the objects' fitted materials, everything insertion needs.

The folder's ``result.json`` records which files were read (``inputs``), the camera, the
transform from the camera frame into the light's room frame and the fit's settings; the light is
``panorama.exr`` (radiance R, G, B and, for a 2.5D light, depth Z) and the materials are
``materials.json``. ``--light METHOD`` picks a compared method's folder (``compare/METHOD``), whose
files have the same layout.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import torch

from roomlight.errors import InputFileError, RoomlightError
from roomlight.core.light import Light

__all__ = ["FittedPhoto", "load_fitted_photo", "fitted_lights", "albedos_divided"]


def albedos_divided(materials: dict, gain: float) -> dict:
    """Fitted objects' materials (by label, each with an ``albedo`` list) with every albedo divided by
    ``gain`` and held at 1: what the photograph says of them under a light ``gain`` times as bright."""
    return {lab: {**m, "albedo": [min(1.0, float(a) / gain) for a in m["albedo"]]} for lab, m in materials.items()}


@dataclass
class FittedPhoto:
    """What ``fit-photo`` recovered from one photograph.

    Attributes:
        folder: the fit's folder (the main method's, or ``compare/METHOD``).
        method: the method that fitted the light.
        case: the photograph (:class:`~roomlight.fitting.photo.case.PhotoCase`), read from the recorded inputs.
        config: the fit's settings (:class:`~roomlight.fitting.photo.config.PhotoFitConfig`).
        light: the fitted light: radiance (H, 2H, 3) linear, depth (H, 2H) metres of the room frame
            (``mesh``) or None (``envmap``); its frame is camera frame -> the light's room frame.
        transform: that frame as the fit's parts (:class:`~roomlight.fitting.photo.geometry.SceneTransform`:
            rotation, scale, translation, as ``result.json`` records them); the photograph's geometry
            is mapped into the room with these.
        materials: fitted material of each object, by mask label: {albedo: [r, g, b], roughness, metallic}.
        exposure_ev: how far the light was moved from the fit's reading, in stops (:meth:`with_exposure`;
            0 = as fitted).

    Raises:
        RoomlightError: the light's frame is not ``transform``.
    """

    folder: Path
    method: str
    case: object
    config: object
    light: Light
    transform: object
    materials: dict[int, dict]
    exposure_ev: float = 0.0

    def __post_init__(self):
        if not np.allclose(self.light.frame, self.transform.matrix):
            raise RoomlightError(f"{self.folder}: the light's frame is not the fit's camera-to-room transform")

    @property
    def kind(self) -> str:
        """``mesh`` (2.5D area light) or ``envmap``."""
        return self.light.kind

    @property
    def radiance(self) -> torch.Tensor:
        """(H, 2H, 3) linear radiance of the light."""
        return self.light.radiance

    @property
    def depth(self) -> torch.Tensor | None:
        """(H, 2H) metres in the room frame, or None for an env map."""
        return self.light.depth

    def with_exposure(self, ev: float) -> "FittedPhoto":
        """The same photograph read with a light 2^ev times as bright and objects 2^-ev times as reflective.

        One photograph cannot tell a light from twice that light on half the albedo, and the photo fit's
        largest error is the light's level (a bright object inserted under too bright a light glows). Moving
        the split by hand keeps the photograph's own reading: the fitted objects' albedos (base colours,
        metals included) are divided by what the light is multiplied by, and the other surfaces' albedo,
        estimated from the photograph under the light, follows by itself. An albedo that would pass 1 is
        held at 1 (that object then reads brighter than in the photograph).

        Raises:
            RoomlightError: ``ev`` not finite or outside [-10, 10].
        """
        light = self.light.with_exposure(ev)
        return replace(self, light=light, materials=albedos_divided(self.materials, 2.0 ** float(ev)),
                       exposure_ev=self.exposure_ev + float(ev))

    def exposure_for_albedo(self, label: int, albedo: float) -> float:
        """The exposure (stops, for :meth:`with_exposure`) at which object ``label`` of the photograph has
        the mean albedo ``albedo`` over R, G, B: a surface of known reflectance in the photograph (a grey
        card, white paper, a painted wall of known paint) fixes the light's level that one photograph
        leaves open.

        Raises:
            RoomlightError: no such object, ``albedo`` outside (0, 1], or a fitted albedo of zero.
        """
        if int(label) not in self.materials:
            known = ", ".join(str(k) for k in sorted(self.materials)) or "none"
            raise RoomlightError(f"--reference-albedo: the photograph has no object {label} (its objects: {known})")
        albedo = float(albedo)
        if not (math.isfinite(albedo) and 0.0 < albedo <= 1.0):
            raise RoomlightError(f"--reference-albedo: an albedo is in (0, 1], got {albedo}")
        fitted = float(np.mean(self.materials[int(label)]["albedo"]))
        if fitted <= 0.0:
            raise RoomlightError(f"--reference-albedo: object {label} was fitted black; it cannot set the level")
        return math.log2(fitted / albedo)

    def bsdfs(self) -> dict[int, dict]:
        """Each fitted object's Mitsuba BSDF dict, by label."""
        from roomlight.core.render.materials import principled_bsdf

        return {lab: principled_bsdf(m["albedo"], m["roughness"], m["metallic"]) for lab, m in self.materials.items()}


def fitted_lights(folder) -> list[str]:
    """The methods whose lights a ``fit-photo`` folder holds: the main one, then the compared ones."""
    folder = Path(folder)
    result = _read_json(folder / "result.json", folder)
    names = [str(result.get("method", "?"))]
    compare = folder / "compare"
    if compare.is_dir():
        names += sorted(p.name for p in compare.iterdir() if (p / "result.json").is_file())
    return names


def _read_json(path: Path, folder: Path) -> dict:
    if not path.is_file():
        raise InputFileError(folder, "not a fit-photo output folder (no result.json); run `roomlight fit-photo` first")
    try:
        data = json.loads(path.read_text())
    except (ValueError, UnicodeDecodeError) as exc:
        raise InputFileError(path, f"not valid JSON ({exc})") from None
    if data.get("format") != "roomlight.photo-fit":
        raise InputFileError(path, f"not a fit-photo result (format {data.get('format')!r})")
    return data


def load_fitted_photo(folder, light: str | None = None) -> FittedPhoto:
    """Read a ``fit-photo`` output folder (``light``: a compared method's name, default the main one)."""
    from roomlight.core.io import read_panorama
    from roomlight.fitting.photo.camera import PhotoCamera
    from roomlight.fitting.photo.case import load_photo
    from roomlight.fitting.photo.config import PhotoFitConfig
    from roomlight.fitting.photo.geometry import SceneTransform

    root = Path(folder)
    main = _read_json(root / "result.json", root)
    if light is not None and light != main.get("method"):
        sub = root / "compare" / light
        if not (sub / "result.json").is_file():
            raise RoomlightError(f"--light {light}: {root} has no such fitted light; it has "
                                 f"{', '.join(fitted_lights(root))}")
        root, result = sub, _read_json(sub / "result.json", sub)
    else:
        result = main
    inputs = result.get("inputs", {})
    cam = result.get("camera", {})
    # A fit without objects (no mask) has no mask file to read again.
    roles = ("image", "depth", "mask") if result.get("objects", [None]) else ("image", "depth")
    missing = [role for role in roles if not inputs.get(role)]
    if missing:
        raise InputFileError(root / "result.json", f"records no {' / '.join(missing)} file: insertion needs the "
                                                   "photograph, its depth and its mask as files",
                             "fit the photograph again with this version of roomlight")
    for role in roles:
        if not Path(inputs[role]).is_file():
            raise InputFileError(inputs[role], f"the fit's {role} file is gone (moved or deleted since the fit)")
    h, w = cam["input_size"]
    k = cam["intrinsics_input"]
    intr = PhotoCamera(int(w), int(h), float(k["fx"]), float(k["fy"]), float(k["cx"]), float(k["cy"]))
    case = load_photo(inputs["image"], depth=inputs["depth"], depth_kind=cam.get("depth_kind"), mask=inputs.get("mask"),
                      normals=inputs.get("normals"), intrinsics=intr, pitch=float(cam.get("pitch_deg", 0.0)),
                      roll=float(cam.get("roll_deg", 0.0)))
    config = PhotoFitConfig.from_dict(result.get("settings", {}), where=str(root / "result.json"))
    t = result["transform"]
    transform = SceneTransform(np.asarray(t["rotation"]), float(t["scale"]), np.asarray(t["translation"]))
    pano = read_panorama(root / "panorama.exr")
    kind = str(result.get("emitter_kind", "mesh"))
    if kind == "mesh" and pano.depth is None:
        raise InputFileError(root / "panorama.exr", "a 2.5D light without depth")
    light = Light(pano.radiance, pano.depth if kind == "mesh" else None, kind, transform.matrix)
    materials = {}
    mat_file = root / "materials.json"
    if mat_file.is_file():
        for m in json.loads(mat_file.read_text()).get("objects", []):
            materials[int(m["label"])] = {"albedo": [float(v) for v in m["albedo"]],
                                          "roughness": float(m["roughness"]), "metallic": float(m["metallic"])}
    return FittedPhoto(root, str(result.get("method")), case, config, light, transform, materials)
