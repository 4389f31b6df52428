"""``roomlight view``: one self-contained HTML page showing a 2.5D area light (see viewer.js).

The page holds everything: three.js (inlined from the pinned npm package, see
:mod:`roomlight.viewer.three`), the viewer module, and the light as base64 arrays: float32
positions and uv, uint32 faces, and the radiance as half floats (RGBA), so the exposure slider
reaches detail above 1. Half floats stop at 65504; larger radiance is clipped there (the page
says how many texels). Nothing is fetched when the page is opened.
"""

from __future__ import annotations

import base64
import html
import json
from pathlib import Path
from string import Template

import numpy as np

from roomlight.core.color import DISPLAY_GAMMA
from roomlight.export.bundle import LightSource

__all__ = ["viewer_payload", "write_viewer"]

HALF_MAX = 65504.0
INSET_WIDTH = 240  #: width in CSS pixels of each probe inset (height is half)


def _b64(a: np.ndarray, dtype) -> str:
    return base64.b64encode(np.ascontiguousarray(a, dtype).tobytes()).decode("ascii")


def _mesh(vertices, faces, uv=None) -> dict:
    m = {"positions": _b64(vertices, "<f4"), "faces": _b64(faces, "<u4")}
    if uv is not None:
        m["uv"] = _b64(uv, "<f4")
    return m


def _scene_probe(light: LightSource):
    """The scene's own probe object (the benchmark's held-out sphere), which the page's probe replaces."""
    return next((o for o in light.objects if o.id == "probe" or o.role == "eval"), None)


def _default_probe(light: LightSource) -> tuple[list[float], float]:
    """Centre and radius of the start probe: the scene's probe, else one 40 % of the way to the wall ahead (-z)."""
    own = _scene_probe(light)
    if own is not None:
        c = own.vertices.mean(0)
        return [float(x) for x in c], float(np.linalg.norm(own.vertices - c, axis=1).max())
    h, w = light.depth.shape
    ahead = float(np.median(light.depth[h // 2 - 1:h // 2 + 1, :max(w // 32, 1)]))
    return [0.0, -0.1 * ahead, -0.4 * ahead], 0.04 * float(np.median(light.depth))


#: Longest side of a fit-photo's backdrop inside the page, pixels.
BACKDROP_SIZE = 960


def _photo_payload(light: LightSource) -> dict | None:
    """A fit-photo's photograph as the page's backdrop (sRGB PNG) and its camera's vertical field of
    view, or None for a light without one."""
    cam = light.camera or {}
    if light.backplate is None or "intrinsics" not in cam:
        return None
    import io

    from PIL import Image

    from roomlight.core.color import linear_to_srgb

    img = Image.fromarray(np.rint(linear_to_srgb(np.clip(light.backplate, 0, 1)) * 255).astype(np.uint8))
    scale = min(1.0, BACKDROP_SIZE / max(img.size))
    if scale < 1:
        img = img.resize((max(1, round(img.width * scale)), max(1, round(img.height * scale))), Image.LANCZOS)
    buf = io.BytesIO()
    img.save(buf, format="PNG")
    k = cam["intrinsics"]
    return {"png": base64.b64encode(buf.getvalue()).decode("ascii"), "width": int(cam["width"]),
            "height": int(cam["height"]), "fov_v": float(np.degrees(2 * np.arctan(cam["height"] / (2 * k["fy"]))))}


def _photo_probe(light: LightSource) -> tuple[list[float], float]:
    """Start probe of a fit-photo: resting on the surface the photograph shows a little below its centre."""
    cam = light.camera
    mesh = next(o for o in light.objects if o.material == "shadow_catcher")
    k, rot = cam["intrinsics"], np.asarray(cam["rotation"], float)
    d_cam = np.array([(0.5 * cam["width"] - k["cx"]) / k["fx"], -(0.7 * cam["height"] - k["cy"]) / k["fy"], -1.0])
    d = rot @ (d_cam / np.linalg.norm(d_cam))
    rel = mesh.vertices.astype(float) - np.asarray(cam["origin"], float)
    t = rel @ d
    off = np.linalg.norm(rel - t[:, None] * d, axis=1) + np.where(t > 0, 0.0, np.inf)
    p = mesh.vertices[int(np.argmin(off))].astype(float)
    dist = float(np.linalg.norm(p - np.asarray(cam["origin"], float)))
    radius = 0.06 * dist
    up = rot[:, 1]
    return (p + up * radius).tolist(), radius


def viewer_payload(light: LightSource, cube_size: int = 128) -> dict:
    """The JSON the page reads: the light, the objects, the start camera, probe and exposure."""
    from roomlight.core.io.preview import auto_exposure_stops

    rad = np.nan_to_num(light.radiance.astype(np.float32), nan=0.0, posinf=HALF_MAX)
    clipped = int((rad > HALF_MAX).any(-1).sum())
    rgba = np.concatenate([np.minimum(rad, HALF_MAX), np.ones_like(rad[..., :1])], -1).astype("<f2")
    lo, hi = light.vertices.min(0), light.vertices.max(0)
    photo = _photo_payload(light)
    probe, radius = _photo_probe(light) if photo else _default_probe(light)
    own = _scene_probe(light)
    cam = light.camera or {"origin": [0.0, 0.0, 0.0], "target": [0.0, 0.0, -1.0], "fov": 65.0}
    origin, target = np.asarray(cam["origin"], float), np.asarray(cam["target"], float)
    return {
        "photo": photo, "up": list(cam.get("up", [0.0, 1.0, 0.0])),
        "source": light.source, "height": int(rad.shape[0]), "width": int(rad.shape[1]),
        "radiance": base64.b64encode(rgba.view("<u2").tobytes()).decode("ascii"), "clipped_texels": clipped,
        "mesh": _mesh(light.vertices, light.faces, light.uv),
        "objects": [{"id": o.id, "role": o.role, "material": o.material, **_mesh(o.vertices, o.faces)}
                    for o in light.objects if o is not own],
        # orbit around a point 1 m ahead of the scene's camera (OrbitControls needs a distinct target)
        "camera": {"origin": origin.tolist(),
                   "target": (origin + (target - origin) / max(np.linalg.norm(target - origin), 1e-9)).tolist()},
        # vertical field of view for three.js: the photograph's, else the scene's horizontal one (square images)
        "fov": photo["fov_v"] if photo else float(cam.get("fov", 65.0)),
        "probe": probe, "probe_radius": max(radius, 0.02), "bounds": [lo.tolist(), hi.tolist()],
        # a photo's light is in the photograph's units: shown as they are, it matches the backdrop
        "exposure_stops": 0.0 if photo else round(float(auto_exposure_stops(light.radiance)), 1),
        "gamma": DISPLAY_GAMMA, "cube_size": int(cube_size), "inset_width": INSET_WIDTH,
    }


def write_viewer(light: LightSource, out, title: str | None = None, cube_size: int = 128) -> Path:
    """Write the viewer page for ``light`` to ``out`` (an .html path); returns the path."""
    from roomlight.viewer.three import module_scripts

    data = viewer_payload(light, cube_size)
    app = (Path(__file__).with_name("viewer.js")).read_text(encoding="utf-8")
    extra = (f" {data['clipped_texels']} texels above {HALF_MAX:g} are shown clipped."
             if data["clipped_texels"] else "")
    if data["photo"]:
        extra += (" The photograph is the backdrop (untick it to see the light); dragging the probe keeps it on the "
                  "surfaces the photograph shows, resting on them.")
    elif data["objects"]:
        extra += f" Scene objects: {', '.join(html.escape(o['id']) for o in data['objects'])} (not lit, shown for place)."
    page = Template((Path(__file__).with_name("page.html")).read_text(encoding="utf-8")).substitute(
        title=html.escape(title or Path(light.source).name), source=html.escape(light.source), extra=extra,
        inset_width=INSET_WIDTH, inset_height=INSET_WIDTH // 2,
        data=json.dumps(data).replace("</", "<\\/"), modules=module_scripts(app))
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(page, encoding="utf-8")
    return out
