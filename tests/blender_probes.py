"""Render probe spheres under an exported roomlight light with Blender's Cycles (run with the Python
that has the ``bpy`` module; used by tests/test_blender.py).

Usage: python blender_probes.py EXPORT SPEC.json OUT_DIR
SPEC: {"camera": {"origin", "target", "up", "fov"}, "width", "height", "samples",
       "probes": [{"name", "center", "radius", "material": "diffuse:A" | "mirror"}]}
Writes OUT_DIR/<name>.exr (linear radiance) for each probe, rendered alone.
"""

import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src" / "roomlight" / "export"))
import blender_setup  # noqa: E402


def main(export, spec_path, out_dir):
    import bpy
    from mathutils import Matrix, Vector

    spec = json.loads(Path(spec_path).read_text())
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    for probe in spec["probes"]:
        info = blender_setup.open_export(export, samples=spec.get("samples", 64))
        scene = bpy.context.scene
        scene.cycles.max_bounces = 4
        scene.cycles.filter_width = 0.01  # a box-like pixel filter, as Mitsuba's renders in the test
        to_blender = blender_setup.roomlight_to_blender(info)
        # the probe
        bpy.ops.mesh.primitive_uv_sphere_add(segments=128, ring_count=64, radius=probe["radius"])
        sphere = bpy.context.active_object
        bpy.ops.object.shade_smooth()
        sphere.matrix_world = to_blender @ Matrix.Translation(Vector(probe["center"])) @ sphere.matrix_basis.to_3x3().to_4x4()
        mat = bpy.data.materials.new("probe")
        mat.use_nodes = True
        nodes = mat.node_tree.nodes
        for n in list(nodes):
            if n.type != "OUTPUT_MATERIAL":
                nodes.remove(n)
        kind, _, value = probe["material"].partition(":")
        if kind == "mirror":
            bsdf = nodes.new("ShaderNodeBsdfGlossy")
            bsdf.inputs["Roughness"].default_value = 0.0
            bsdf.inputs["Color"].default_value = (1, 1, 1, 1)
        else:
            bsdf = nodes.new("ShaderNodeBsdfDiffuse")
            a = float(value)
            bsdf.inputs["Color"].default_value = (a, a, a, 1)
            bsdf.inputs["Roughness"].default_value = 0.0
        out_node = next(n for n in nodes if n.type == "OUTPUT_MATERIAL")
        mat.node_tree.links.new(bsdf.outputs[0], out_node.inputs["Surface"])
        sphere.data.materials.append(mat)
        # the camera, in roomlight's frame then through the importer's axes
        cam = spec["camera"]
        o, t, u = Vector(cam["origin"]), Vector(cam["target"]), Vector(cam["up"])
        f = (t - o).normalized()
        r = f.cross(u).normalized()
        up = r.cross(f)
        pose = Matrix(((r.x, up.x, -f.x, o.x), (r.y, up.y, -f.y, o.y), (r.z, up.z, -f.z, o.z), (0, 0, 0, 1)))
        cam_data = bpy.data.cameras.new("probe_camera")
        cam_data.sensor_fit = "HORIZONTAL"
        import math

        cam_data.angle = math.radians(cam["fov"])
        cam_obj = bpy.data.objects.new("probe_camera", cam_data)
        scene.collection.objects.link(cam_obj)
        cam_obj.matrix_world = to_blender @ pose
        scene.camera = cam_obj
        scene.render.resolution_x, scene.render.resolution_y = spec["width"], spec["height"]
        scene.render.resolution_percentage = 100
        scene.render.film_transparent = False
        scene.render.image_settings.file_format = "OPEN_EXR"
        scene.render.image_settings.color_depth = "32"
        scene.render.filepath = str((out / f"{probe['name']}.exr").resolve())
        bpy.ops.render.render(write_still=True)


if __name__ == "__main__":
    main(*sys.argv[1:4])
