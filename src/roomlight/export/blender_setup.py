"""Open a roomlight export (USD or glTF binary) in Blender, ready to render with Cycles.

This file runs inside Blender's Python and imports nothing from roomlight, so it can be used
where roomlight is not installed:

    blender --python blender_setup.py -- light.usda           # Blender's own executable
    python blender_setup.py light.usda --render out.exr        # the ``bpy`` module from PyPI

It imports the file and then:

- checks that the 2.5D light's material emits its texture at the exported strength: USD's texture
  is the float radiance at strength 1, glTF's an 8-bit sRGB texture at strength s
  (``KHR_materials_emissive_strength``), which this script replaces by the float texture written
  beside it (``<stem>_radiance.exr``); either way a texel shows roomlight's radiance, the same
  number as ``radiance.exr``, so a render in Blender has roomlight's brightness with no exposure
  change (the view transform is set to Standard);
- makes the world black: all the light is in the emissive mesh;
- for a ``fit-photo`` export: makes the photograph's camera the scene camera at the photograph's
  size, and marks the depth mesh as a Cycles shadow catcher, so objects added to the scene cast
  their shadows onto the photograph when the render is composited over the backplate
  (``<stem>_backplate.png``, written beside the export).

Functions: :func:`open_export` (the above, returns what it found) and :func:`roomlight_to_blender`
(the matrix that takes roomlight's coordinates, y up, into the imported scene's, z up).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path


def _bpy():
    import bpy  # noqa: F401  (only inside Blender, or with the bpy module installed)

    return bpy


def roomlight_to_blender(info: dict):
    """The 4 x 4 matrix (mathutils) from roomlight's frame (metres, y up, capture point at the origin)
    to Blender's world (z up) for an :func:`open_export` result: points p go to M @ p.

    Both importers map roomlight's (x, y, z) to Blender's (x, -z, y): the USD importer with the
    object's transform, the glTF importer by converting the vertices themselves (the object's
    transform stays the identity)."""
    from mathutils import Matrix

    if info["format"] == "gltf":
        return Matrix(((1, 0, 0, 0), (0, 0, -1, 0), (0, 1, 0, 0), (0, 0, 0, 1)))
    return info["light"].matrix_world.copy()


def _material_nodes(obj):
    """Every shader node of the object's node-based materials."""
    for slot in obj.material_slots:
        mat = slot.material
        if mat is not None and mat.use_nodes:
            yield from mat.node_tree.nodes


def _emissive_strength(obj) -> None:
    """The light emits its texture times the exported strength: the glTF importer sets the strength
    from ``KHR_materials_emissive_strength``, the USD importer sets 1 (the texture is the float
    radiance); a strength of 0 (an importer that drops it) is set to 1."""
    for node in _material_nodes(obj):
        if node.type == "BSDF_PRINCIPLED":
            emission = node.inputs.get("Emission Color") or node.inputs.get("Emission")
            if emission is not None and emission.is_linked:
                if node.inputs["Emission Strength"].default_value == 0.0:
                    node.inputs["Emission Strength"].default_value = 1.0
                # nothing but emission: the light is not lit by itself
                node.inputs["Base Color"].default_value = (0.0, 0.0, 0.0, 1.0)
                if "Specular IOR Level" in node.inputs:
                    node.inputs["Specular IOR Level"].default_value = 0.0


def _float_texture(obj, exr: Path) -> bool:
    """Show the exact float radiance (``<stem>_radiance.exr``) instead of a glTF's 8-bit texture, at
    strength 1. Cycles interpolates 8-bit sRGB textures before decoding them, which darkens the
    texels next to a bright window: about 8 % of the mean radiance on a 32 x 64 light (measured)."""
    bpy = _bpy()
    if not exr.is_file():
        return False
    image = bpy.data.images.load(str(exr), check_existing=True)
    image.colorspace_settings.name = "Non-Color"
    done = False
    for node in _material_nodes(obj):
        if node.type == "TEX_IMAGE":
            node.image = image
            done = True
        elif node.type == "BSDF_PRINCIPLED":
            node.inputs["Emission Strength"].default_value = 1.0
    return done


def _gltf_extras(path: Path) -> dict:
    """The JSON chunk of a .glb file."""
    import struct

    data = path.read_bytes()
    n = struct.unpack("<I", data[12:16])[0]
    return json.loads(data[20:20 + n])


def open_export(path, samples: int = 64) -> dict:
    """Import ``path`` into an empty scene and set it up (module docstring).

    Returns ``{"light": object, "camera": object or None, "depth_mesh": object or None,
    "resolution": (w, h) or None, "backplate": path or None, "format": "usd" or "gltf"}``.
    """
    bpy = _bpy()
    path = Path(path).resolve()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    if path.suffix.lower() in (".usd", ".usda", ".usdc"):
        bpy.ops.wm.usd_import(filepath=str(path))
    elif path.suffix.lower() in (".glb", ".gltf"):
        bpy.ops.import_scene.gltf(filepath=str(path))
    else:
        raise SystemExit(f"{path}: expected a .usd/.usda/.usdc or .glb file written by `roomlight export`")
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = int(samples)
    scene.cycles.use_denoising = False
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    world = bpy.data.worlds.new("roomlight_black")
    world.use_nodes = True
    bg = world.node_tree.nodes.get("Background")
    if bg is not None:
        bg.inputs["Strength"].default_value = 0.0
    scene.world = world

    light = camera = depth = None
    for obj in scene.objects:
        name = obj.name.lower()
        if obj.type == "MESH" and ("arealight" in name or "area_light" in name):
            light = obj
        elif obj.type == "MESH" and ("depthmesh" in name or "depth_mesh" in name):
            depth = obj
        elif obj.type == "CAMERA":
            camera = obj
    if light is None:
        raise SystemExit(f"{path}: no 2.5D light (a mesh called AreaLight / area_light) in the file")
    _emissive_strength(light)
    fmt = "usd" if path.suffix.lower().startswith(".usd") else "gltf"
    info = {"light": light, "camera": camera, "depth_mesh": depth, "resolution": None, "backplate": None,
            "format": fmt, "float_texture": False}
    if fmt == "gltf" and path.suffix.lower() == ".glb":
        exr = _gltf_extras(path).get("extras", {}).get("roomlight", {}).get("radiance_exr")
        info["float_texture"] = bool(exr) and _float_texture(light, path.with_name(exr))
    if depth is not None:
        depth.is_shadow_catcher = True
    extras = _photo_extras(path)
    if camera is not None:
        scene.camera = camera
        if extras.get("resolution"):
            w, h = extras["resolution"]
            scene.render.resolution_x, scene.render.resolution_y = int(w), int(h)
            scene.render.resolution_percentage = 100
            info["resolution"] = (int(w), int(h))
            camera.data.sensor_fit = "HORIZONTAL"
        if extras.get("backplate"):
            info["backplate"] = str(path.with_name(extras["backplate"]))
            scene.render.film_transparent = True  # composite the render over the backplate
    return info


def _photo_extras(path: Path) -> dict:
    """The camera's resolution and backplate as the export recorded them."""
    if path.suffix.lower() == ".glb":
        doc = _gltf_extras(path)
        for node in doc.get("nodes", []):
            r = node.get("extras", {}).get("roomlight", {})
            if "camera" in node and r:
                return {"resolution": r.get("resolution"), "backplate": r.get("backplate")}
        return {}
    try:
        from pxr import Usd
    except ImportError:  # Blender's own Python has no pxr module; the importer read the camera anyway
        return {}
    prim = Usd.Stage.Open(str(path)).GetPrimAtPath("/World/Camera")
    if not prim:
        return {}
    res = prim.GetCustomDataByKey("roomlight:resolution")
    return {"resolution": list(res) if res is not None else None,
            "backplate": prim.GetCustomDataByKey("roomlight:backplate")}


def main(argv: list[str]) -> None:
    import argparse

    if "--" in argv:  # blender --python blender_setup.py -- FILE ...
        argv = argv[argv.index("--") + 1:]
    ap = argparse.ArgumentParser(description="Open a roomlight export in Blender, ready for Cycles.")
    ap.add_argument("file", help="a .usda / .usd / .glb written by `roomlight export`")
    ap.add_argument("--render", default=None, help="render the photograph's camera to this file (EXR or PNG)")
    ap.add_argument("--samples", type=int, default=64)
    args = ap.parse_args(argv)
    info = open_export(args.file, args.samples)
    if args.render:
        bpy = _bpy()
        scene = bpy.context.scene
        if scene.camera is None:
            raise SystemExit("the file has no camera to render from (export a fit-photo folder)")
        scene.render.filepath = str(Path(args.render).resolve())
        scene.render.image_settings.file_format = "OPEN_EXR" if args.render.lower().endswith(".exr") else "PNG"
        bpy.ops.render.render(write_still=True)
    print(json.dumps({k: (v.name if hasattr(v, "name") else v) for k, v in info.items()}))


if __name__ == "__main__":
    main(sys.argv[1:] if "--" not in sys.argv else sys.argv)
