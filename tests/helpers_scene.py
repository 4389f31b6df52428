"""A tiny inverse-rendering scene made on the fly: the example room as the true emitter."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from roomlight.core.examples import example_room
from roomlight.core.io import save_png, write_exr, write_panorama
from roomlight.fitting.scene.description import parse_scene, save_scene


def make_tiny_scene(root: Path, height: int = 16, res: int = 40, spp: int = 256, material: str = "diffuse",
                    light=None):
    """Write a scene (two objects in the input view) whose target is rendered under the example
    room's 2.5D area light, or under ``light`` = (radiance (h, 2h, 3), depth (h, 2h)) when given;
    returns (scene, true radiance, true depth)."""
    from roomlight.core.render.scene import EmitterScene
    from roomlight.fitting.scene.build import view_objects

    root = Path(root)
    root.mkdir(parents=True, exist_ok=True)
    rad, depth = example_room(height) if light is None else (light[0].float(), light[1].float())
    height = rad.shape[0]
    write_panorama(root / "gt.exr", (rad.numpy(), depth.numpy()), half=False)
    camera = {"origin": [0, 0, 0], "target": [0, -0.4, -1], "fov": 65, "width": res, "height": res}
    data = {
        "objects": [
            {"id": "a", "shape": "knot", "translate": [-0.35, -0.45, -1.4], "scale": 0.25, "material": material},
            {"id": "b", "shape": "blob", "translate": [0.4, -0.5, -1.7], "scale": 0.3, "material": material},
        ],
        "views": {"input": {"camera": camera, "objects": ["a", "b"]}},
        "emitter": {"panorama": "gt.exr"},
    }
    scene = parse_scene(data, root)
    es = EmitterScene("mesh", (height, 2 * height), objects=view_objects(scene, "input"),
                      sensor=scene.view("input").camera.sensor(), integrator={"type": "prb", "max_depth": 4})
    es.set_emitter(rad, depth)
    img = es.render(spp=spp, seed=123).numpy()
    write_exr(root / "input.exr", {c: img[..., i] for i, c in enumerate("RGB")})
    ldr = (np.clip(img, 0, 1) ** (1 / 2.2) * 255 + 0.5).astype(np.uint8)
    save_png(root / "input.png", ldr)
    data["views"]["input"].update({"image": "input.exr", "ldr": "input.png"})
    mask = _object_mask(scene, res)
    save_png(root / "mask.png", (mask * 255).astype(np.uint8))
    data["views"]["input"]["mask"] = "mask.png"
    scene = parse_scene(data, root)
    save_scene(scene, root / "scene.json")
    return scene, rad, depth


def _object_mask(scene, res: int) -> np.ndarray:
    """(res, res) bool: camera rays through pixel centres that hit an object (the emitter is
    background)."""
    from roomlight.core.render.variant import mitsuba
    from roomlight.core.geometry.projection import perspective_directions
    from roomlight.fitting.scene.build import view_objects

    mi = mitsuba()
    cam = scene.view("input").camera
    fwd = np.asarray(cam.target) - np.asarray(cam.origin)
    d = perspective_directions(res, res, cam.fov, forward=fwd, up=cam.up).reshape(-1, 3).numpy()
    s = mi.load_dict({"type": "scene", **view_objects(scene, "input")})
    o = np.broadcast_to(np.asarray(cam.origin, np.float32), d.shape)
    ray = mi.Ray3f(mi.Point3f(o[:, 0], o[:, 1], o[:, 2]), mi.Vector3f(d[:, 0], d[:, 1], d[:, 2]))
    hit = np.array(s.ray_intersect(ray).is_valid())
    return hit.reshape(res, res)
