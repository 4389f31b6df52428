"""The light exported to Blender renders with roomlight's brightness (Cycles on the CPU against Mitsuba).

Needs a Python with Blender's ``bpy`` module (PyPI: bpy, Python 3.11): ``.venv-blender/bin/python``
(``make blender``) or ``$ROOMLIGHT_BLENDER_PYTHON``. Skipped with the reason where there is none."""

from __future__ import annotations

import json
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
PROBE = {"center": [0.3, -0.5, -1.6], "radius": 0.4}
CAMERA = {"origin": [0.0, -0.2, 0.0], "target": PROBE["center"], "up": [0.0, 1.0, 0.0], "fov": 36.0}
SIZE = 40


def blender_python() -> str | None:
    cand = os.environ.get("ROOMLIGHT_BLENDER_PYTHON") or str(ROOT / ".venv-blender" / "bin" / "python")
    if not Path(cand).is_file():
        return None
    ok = subprocess.run([cand, "-c", "import bpy"], capture_output=True, timeout=120).returncode == 0
    return cand if ok else None


def _disc(shrink: float = 0.8) -> np.ndarray:
    """(SIZE, SIZE) pixels well inside the probe's silhouette (the rim mixes probe and room)."""
    o, c = np.array(CAMERA["origin"]), np.array(PROBE["center"])
    alpha = np.arcsin(PROBE["radius"] / np.linalg.norm(c - o))
    t = np.tan(np.radians(CAMERA["fov"]) / 2)
    x = ((np.arange(SIZE) + 0.5) / SIZE * 2 - 1) * t
    xx, yy = np.meshgrid(x, x)
    return np.arctan(np.hypot(xx, yy)) < shrink * alpha


def _mitsuba(radiance, depth, bsdf: dict, spp: int) -> np.ndarray:
    import torch

    from roomlight.core.render.camera import perspective_sensor
    from roomlight.core.render.scene import EmitterScene

    sensor = perspective_sensor(CAMERA["origin"], CAMERA["target"], CAMERA["up"], CAMERA["fov"], SIZE, SIZE)
    es = EmitterScene("mesh", tuple(radiance.shape[:2]), objects={"probe": {"type": "sphere", **PROBE, "bsdf": bsdf}},
                      sensor=sensor, integrator={"type": "path", "max_depth": 5})
    es.set_emitter(torch.as_tensor(radiance), torch.as_tensor(depth))
    return es.render(spp=spp, seed=1).numpy()


@pytest.mark.mitsuba
@pytest.mark.slow
@pytest.mark.parametrize("fmt", ["usda", "glb"])
def test_a_probe_in_blender_has_roomlights_brightness_and_mirrors_the_same_room(tmp_path, fmt):
    py = blender_python()
    if py is None:
        pytest.skip("no Python with Blender's bpy module (make blender, or set ROOMLIGHT_BLENDER_PYTHON)")
    from roomlight.core.examples import example_room
    from roomlight.export import export_light, load_light
    from roomlight.core.io import read_exr, write_panorama

    rad, depth = example_room(32)
    write_panorama(tmp_path / "room.exr", (rad.numpy(), depth.numpy()), half=False)
    out = tmp_path / f"light.{fmt}"
    export_light(load_light(tmp_path / "room.exr"), out)
    spec = {"camera": CAMERA, "width": SIZE, "height": SIZE, "samples": 256,
            "probes": [{"name": "diffuse", **PROBE, "material": "diffuse:0.8"},
                       {"name": "mirror", **PROBE, "material": "mirror"}]}
    (tmp_path / "spec.json").write_text(json.dumps(spec))
    r = subprocess.run([py, str(ROOT / "tests" / "blender_probes.py"), str(out), str(tmp_path / "spec.json"),
                        str(tmp_path / "blender")], capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    disc = _disc()
    ref = {"diffuse": _mitsuba(rad, depth, {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.8] * 3}}, 1024),
           "mirror": _mitsuba(rad, depth, {"type": "conductor", "material": "none"}, 256)}
    for name, mitsuba_img in ref.items():
        ch = read_exr(tmp_path / "blender" / f"{name}.exr")
        blender_img = np.stack([ch[c] for c in "RGB"], -1)
        assert blender_img.shape == mitsuba_img.shape
        m_b, m_m = blender_img[disc].mean(0), mitsuba_img[disc].mean(0)
        np.testing.assert_allclose(m_b, m_m, rtol=0.05, err_msg=f"{name}: Blender {m_b} vs Mitsuba {m_m}")
        if name == "mirror":  # the same part of the room, pixel for pixel
            lb, lm = blender_img[disc].mean(1), mitsuba_img[disc].mean(1)
            assert np.corrcoef(lb, lm)[0, 1] > 0.9
