"""The crop benchmark's spheres in Blender Cycles against Mitsuba: how much the renderer decides the scores.

For each truth panorama of a crop set (normalised as the protocol scores it), the three spheres are rendered
by roomlight's Mitsuba scene (one-lobe matte, a mirror without Fresnel) and by Cycles with the field's own
materials (principled diffuse base 0.8, roughness 0.364, specular 0.5; matte silver: a principled metal of
roughness 0.327 mixed with a glossy lobe of roughness 0.369 through a Fresnel factor of IOR 6.55; mirror: a
principled metal of base 0.8 at roughness 0), same camera and framing. Printed: per sphere, the si-RMSE and
the angular error between the two renders (the protocol's own numbers, with Cycles as the "truth"), and the
ratio of their mean radiance, as means over the panoramas.

Needs a Python with Blender's ``bpy`` (``make blender``: ``.venv-blender/bin/python``, or
``$ROOMLIGHT_BLENDER_PYTHON``).

Run: .venv/bin/python benchmarks/crop_spheres_cycles.py bench/crops-rooms [--n 6] [--samples 512]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]

# Runs inside Blender's Python. Roomlight's axes are y up; Blender's z up. Measured by rendering a panorama
# that encodes roomlight's directions: Cycles shows roomlight's (x, y, z) in Blender's direction (z, x, y).
_BPY = r'''
import bpy, json, math, sys
import numpy as np
from mathutils import Vector
a = json.loads(sys.argv[-1])
bpy.ops.wm.read_factory_settings(use_empty=True)
sc = bpy.context.scene
sc.render.engine = "CYCLES"; sc.cycles.device = "CPU"; sc.cycles.samples = a["samples"]; sc.cycles.seed = 1
sc.cycles.max_bounces = 3; sc.cycles.use_denoising = False
sc.render.resolution_x = sc.render.resolution_y = a["size"]; sc.render.resolution_percentage = 100
sc.view_settings.view_transform = "Standard"; sc.render.film_transparent = False
sc.render.image_settings.file_format = "OPEN_EXR"; sc.render.image_settings.color_depth = "32"
w = bpy.data.worlds.new("w"); w.use_nodes = True; nt = w.node_tree
env = nt.nodes.new("ShaderNodeTexEnvironment"); env.image = bpy.data.images.load(a["panorama"])
env.image.colorspace_settings.name = "Non-Color"; env.interpolation = "Linear"
nt.links.new(env.outputs["Color"], nt.nodes["Background"].inputs["Color"]); sc.world = w
bpy.ops.mesh.primitive_uv_sphere_add(radius=1.0, segments=256, ring_count=128)
sphere = bpy.context.active_object; bpy.ops.object.shade_smooth()
f = a["forward"]; fb = Vector((f[2], f[0], f[1]))
camd = bpy.data.cameras.new("c"); cam = bpy.data.objects.new("c", camd); sc.collection.objects.link(cam); sc.camera = cam
camd.angle = math.radians(a["fov"]); camd.sensor_fit = "HORIZONTAL"; camd.clip_end = 100.0
cam.location = -a["distance"] * fb
cam.rotation_euler = fb.to_track_quat("-Z", "Y").to_euler()
def principled(base, rough, metal, spec=0.5):
    m = bpy.data.materials.new("p"); m.use_nodes = True; p = m.node_tree.nodes["Principled BSDF"]
    p.inputs["Base Color"].default_value = (base, base, base, 1); p.inputs["Roughness"].default_value = rough
    p.inputs["Metallic"].default_value = metal; p.inputs["Specular IOR Level"].default_value = spec
    return m
def matte():
    m = principled(0.8, 0.3271, 1.0); t = m.node_tree; p = t.nodes["Principled BSDF"]; out = t.nodes["Material Output"]
    g = t.nodes.new("ShaderNodeBsdfGlossy"); g.inputs["Roughness"].default_value = 0.369
    fr = t.nodes.new("ShaderNodeFresnel"); fr.inputs["IOR"].default_value = 6.55
    mix = t.nodes.new("ShaderNodeMixShader")
    t.links.new(fr.outputs["Fac"], mix.inputs[0]); t.links.new(p.outputs[0], mix.inputs[1]); t.links.new(g.outputs[0], mix.inputs[2])
    t.links.new(mix.outputs[0], out.inputs["Surface"])
    return m
mats = {"diffuse": principled(0.8, 0.364, 0.0), "matte": matte(), "mirror": principled(0.8, 0.0, 1.0)}
for name, m in mats.items():
    sphere.data.materials.clear(); sphere.data.materials.append(m)
    sc.render.filepath = a["out"] + "/" + name + ".exr"
    bpy.ops.render.render(write_still=True)
'''


def blender_python() -> str | None:
    cand = os.environ.get("ROOMLIGHT_BLENDER_PYTHON") or str(ROOT / ".venv-blender" / "bin" / "python")
    return cand if Path(cand).is_file() else None


def cycles_spheres(pano: np.ndarray, python: str, samples: int, size: int) -> dict[str, np.ndarray]:
    from roomlight.core.io import read_exr, write_exr
    from roomlight.evaluation.crops.protocol import CROP_FORWARD, SPHERE_DISTANCE, _sphere_fov

    with tempfile.TemporaryDirectory() as tmp:
        write_exr(Path(tmp) / "pano.exr", {c: pano[..., i] for i, c in enumerate("RGB")}, half=False)
        (Path(tmp) / "render.py").write_text(_BPY)
        args = {"panorama": str(Path(tmp) / "pano.exr"), "out": tmp, "samples": samples, "size": size,
                "forward": list(CROP_FORWARD), "distance": SPHERE_DISTANCE, "fov": _sphere_fov()}
        r = subprocess.run([python, str(Path(tmp) / "render.py"), "--", json.dumps(args)], capture_output=True,
                           text=True, timeout=1800)
        if r.returncode != 0:
            raise RuntimeError(r.stderr[-2000:])
        out = {}
        for name in ("diffuse", "matte", "mirror"):
            ch = read_exr(Path(tmp) / f"{name}.exr")
            out[name] = np.stack([ch[c] for c in "RGB"], -1).astype(np.float32)
        return out


def main(argv=None) -> None:
    from roomlight.evaluation.crops.bench import _read_truth
    from roomlight.evaluation.crops.metrics import sphere_angular_error, sphere_si_rmse
    from roomlight.evaluation.crops.protocol import render_spheres, score_panorama, sphere_mask

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("crops", type=Path)
    ap.add_argument("--n", type=int, default=6)
    ap.add_argument("--samples", type=int, default=512)
    ap.add_argument("--size", type=int, default=128)
    args = ap.parse_args(argv)
    py = blender_python()
    if py is None:
        sys.exit("no Python with Blender's bpy (make blender, or set ROOMLIGHT_BLENDER_PYTHON)")
    rows = {m: {"si_rmse": [], "angular_error": [], "ratio": []} for m in ("diffuse", "matte", "mirror")}
    names = sorted(p.parent.name for p in args.crops.glob("*/crop.json"))[:args.n]
    mask = sphere_mask(args.size)
    inner = mask.copy()  # the mean ratio over the sphere away from its rim
    for name in names:
        pano = score_panorama(_read_truth(args.crops / name))
        mi = render_spheres(pano, size=args.size, spp=args.samples)
        cy = cycles_spheres(pano, py, args.samples, args.size)
        for m in rows:
            rows[m]["si_rmse"].append(sphere_si_rmse(mi[m], cy[m], mask))
            rows[m]["angular_error"].append(sphere_angular_error(mi[m], cy[m], mask))
            rows[m]["ratio"].append(float(mi[m][inner].mean() / max(cy[m][inner].mean(), 1e-9)))
        print(f"{name}: " + ", ".join(f"{m} si-RMSE {rows[m]['si_rmse'][-1]:.3f} ratio {rows[m]['ratio'][-1]:.3f}"
                                      for m in rows), file=sys.stderr, flush=True)
    print(f"| sphere | si-RMSE Mitsuba vs Cycles | angular error (°) | Mitsuba / Cycles mean radiance | panoramas |")
    print("|---|:---:|:---:|:---:|---:|")
    for m, r in rows.items():
        print(f"| {m} | {np.mean(r['si_rmse']):.3f} | {np.mean(r['angular_error']):.2f} | "
              f"{np.mean(r['ratio']):.3f} ({min(r['ratio']):.3f}–{max(r['ratio']):.3f}) | {len(names)} |")


if __name__ == "__main__":
    main()
