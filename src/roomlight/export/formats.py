"""The 2.5D area light in formats other tools read: glTF 2.0 binary, USD, OBJ + MTL.

Every export writes, next to the scene file, ``<stem>_radiance.exr``: the emissive texture as
float32 linear radiance (R, G, B), the exact values. Formats that take 8-bit textures
(glTF, OBJ) also get ``<stem>_emission.png``: the radiance divided by its largest channel value
``s`` (the *emissive strength*), sRGB-encoded. Radiance is recovered as

    radiance = srgb_to_linear(texel / 255) × s

in the bundle's units (linear Rec.709 radiance, the same numbers as ``radiance.exr``), to within
8-bit quantisation (at most 0.45 % of ``s``). Positions are metres, y up, the capture point at
the origin; faces face inward, so materials are double-sided.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from roomlight.export.bundle import LightSource

__all__ = ["FORMATS", "emission_strength", "linear_to_srgb", "export_light"]

FORMATS = ("glb", "usd", "obj")


def linear_to_srgb(x: np.ndarray) -> np.ndarray:
    """The sRGB transfer function (IEC 61966-2-1) on [0, 1]."""
    x = np.clip(x, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def emission_strength(radiance: np.ndarray) -> float:
    """The scale that maps the radiance into [0, 1]: its largest channel value (1 for a black map)."""
    peak = float(np.max(radiance)) if radiance.size else 0.0
    return peak if np.isfinite(peak) and peak > 0 else 1.0


def _write_textures(light: LightSource, out: Path, png: bool) -> dict[str, Path]:
    from roomlight.core.io import save_png, write_exr

    paths = {"radiance": out.with_name(f"{out.stem}_radiance.exr")}
    r = light.radiance
    write_exr(paths["radiance"], {"R": r[..., 0], "G": r[..., 1], "B": r[..., 2]}, half=False)
    if png:
        paths["emission"] = out.with_name(f"{out.stem}_emission.png")
        texel = np.round(linear_to_srgb(r / emission_strength(r)) * 255).astype(np.uint8)
        save_png(paths["emission"], texel)
    return paths


def _extras(light: LightSource, files: dict[str, Path]) -> dict:
    extras = {"source": light.source, "emissive_strength": emission_strength(light.radiance),
              "radiance_exr": files["radiance"].name, "resolution": list(light.radiance.shape[:2]),
              "units": "metres; linear Rec.709 radiance = srgb_to_linear(texel) * emissive_strength"}
    if light.metadata.get("exposure_ev"):         # moved by hand from the light's source (export --exposure)
        extras["exposure_ev"] = float(light.metadata["exposure_ev"])
    return extras


def _quaternion(r: np.ndarray) -> list[float]:
    """(x, y, z, w) unit quaternion of a (3, 3) rotation matrix."""
    m = np.asarray(r, np.float64)
    w = np.sqrt(max(0.0, 1.0 + m[0, 0] + m[1, 1] + m[2, 2])) / 2
    x = np.copysign(np.sqrt(max(0.0, 1.0 + m[0, 0] - m[1, 1] - m[2, 2])) / 2, m[2, 1] - m[1, 2])
    y = np.copysign(np.sqrt(max(0.0, 1.0 - m[0, 0] + m[1, 1] - m[2, 2])) / 2, m[0, 2] - m[2, 0])
    z = np.copysign(np.sqrt(max(0.0, 1.0 - m[0, 0] - m[1, 1] + m[2, 2])) / 2, m[1, 0] - m[0, 1])
    q = np.array([x, y, z, w])
    return (q / np.linalg.norm(q)).tolist()


def _write_glb(light: LightSource, out: Path) -> dict[str, Path]:
    import pygltflib as g

    files = _write_textures(light, out, png=True)
    blobs: list[bytes] = []
    views, accessors = [], []
    offset = 0

    def add(blob: bytes, target=None) -> int:
        nonlocal offset
        views.append(g.BufferView(buffer=0, byteOffset=offset, byteLength=len(blob), target=target))
        blobs.append(blob + b"\0" * ((-len(blob)) % 4))
        offset += len(blobs[-1])
        return len(views) - 1

    def accessor(array: np.ndarray, kind, ctype, target, bounds: bool = False) -> int:
        view = add(array.tobytes(), target)
        extra = {"min": array.min(0).tolist(), "max": array.max(0).tolist()} if bounds else {}
        accessors.append(g.Accessor(bufferView=view, componentType=ctype, count=len(array), type=kind, **extra))
        return len(accessors) - 1

    pos = accessor(np.ascontiguousarray(light.vertices, np.float32), g.VEC3, g.FLOAT, g.ARRAY_BUFFER, True)
    uv = accessor(np.ascontiguousarray(light.uv, np.float32), g.VEC2, g.FLOAT, g.ARRAY_BUFFER)
    idx = accessor(np.ascontiguousarray(light.faces, np.uint32).reshape(-1), g.SCALAR, g.UNSIGNED_INT,
                   g.ELEMENT_ARRAY_BUFFER)
    png_view = add(files["emission"].read_bytes())
    strength = emission_strength(light.radiance)
    materials = [g.Material(
        name="roomlight_area_light", doubleSided=True, emissiveFactor=[1.0, 1.0, 1.0],
        emissiveTexture=g.TextureInfo(index=0),
        pbrMetallicRoughness=g.PbrMetallicRoughness(baseColorFactor=[0, 0, 0, 1], metallicFactor=0.0,
                                                    roughnessFactor=1.0),
        extensions={"KHR_materials_emissive_strength": {"emissiveStrength": strength}})]
    meshes = [g.Mesh(name="area_light", primitives=[g.Primitive(attributes=g.Attributes(POSITION=pos, TEXCOORD_0=uv),
                                                                indices=idx, material=0)])]
    nodes = [g.Node(mesh=0, name="area_light")]
    cameras = []
    for obj in light.objects:
        if obj.material != "shadow_catcher":
            continue
        p = accessor(np.ascontiguousarray(obj.vertices, np.float32), g.VEC3, g.FLOAT, g.ARRAY_BUFFER, True)
        i = accessor(np.ascontiguousarray(obj.faces, np.uint32).reshape(-1), g.SCALAR, g.UNSIGNED_INT,
                     g.ELEMENT_ARRAY_BUFFER)
        materials.append(g.Material(name="shadow_catcher", doubleSided=True, pbrMetallicRoughness=g.PbrMetallicRoughness(
            baseColorFactor=[0.5, 0.5, 0.5, 1], metallicFactor=0.0, roughnessFactor=1.0)))
        meshes.append(g.Mesh(name="depth_mesh", primitives=[g.Primitive(attributes=g.Attributes(POSITION=p), indices=i,
                                                                         material=len(materials) - 1)]))
        nodes.append(g.Node(mesh=len(meshes) - 1, name="depth_mesh", extras={"roomlight": {"shadow_catcher": True}}))
    if light.camera is not None and "intrinsics" in light.camera:
        c = light.camera
        cameras.append(g.Camera(type="perspective", name="photo", perspective=g.Perspective(
            yfov=float(2 * np.arctan(c["height"] / (2 * c["intrinsics"]["fy"]))), aspectRatio=c["width"] / c["height"],
            znear=0.01, zfar=1000.0)))
        extras = {"roomlight": {"intrinsics": c["intrinsics"], "resolution": [c["width"], c["height"]]}}
        if light.backplate is not None:
            files.update(_write_backplate(light, out))
            extras["roomlight"].update(backplate=files["backplate"].name, backplate_exr=files["backplate_exr"].name)
        nodes.append(g.Node(camera=0, name="photo_camera", rotation=_quaternion(c["rotation"]),
                            translation=[float(v) for v in c["origin"]], extras=extras))
    data = b"".join(blobs)
    gltf = g.GLTF2(
        asset=g.Asset(generator="roomlight", version="2.0"),
        extensionsUsed=["KHR_materials_emissive_strength"],
        scene=0, scenes=[g.Scene(nodes=list(range(len(nodes))))], nodes=nodes, meshes=meshes, cameras=cameras or None,
        accessors=accessors, bufferViews=views, buffers=[g.Buffer(byteLength=len(data))],
        images=[g.Image(bufferView=png_view, mimeType="image/png", name="emission")],
        # u wraps (the seam column has u = 1 + 0.5/W), v stops at the poles
        samplers=[g.Sampler(magFilter=g.LINEAR, minFilter=g.LINEAR, wrapS=g.REPEAT, wrapT=g.CLAMP_TO_EDGE)],
        textures=[g.Texture(source=0, sampler=0)], materials=materials,
        extras={"roomlight": _extras(light, files)})
    gltf.set_binary_blob(data)
    gltf.save_binary(str(out))
    files["emission"].unlink()  # it is inside the .glb
    del files["emission"]
    return {"scene": out, **files}


def _usd_mesh(stage, path: str, vertices, faces):
    """A double-sided triangle ``UsdGeom.Mesh`` at ``path`` (no subdivision)."""
    from pxr import UsdGeom, Vt

    mesh = UsdGeom.Mesh.Define(stage, path)
    mesh.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(np.ascontiguousarray(vertices, np.float32)))
    mesh.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(np.full(len(faces), 3, np.int32)))
    mesh.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(np.ascontiguousarray(faces, np.int32).ravel()))
    mesh.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
    mesh.CreateDoubleSidedAttr(True)
    return mesh


def _write_usd(light: LightSource, out: Path) -> dict[str, Path]:
    from pxr import Gf, Sdf, Usd, UsdGeom, UsdShade, Vt

    files = _write_textures(light, out, png=False)
    stage = Usd.Stage.CreateNew(str(out))
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y)
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    world = UsdGeom.Xform.Define(stage, "/World")
    stage.SetDefaultPrim(world.GetPrim())
    mesh = _usd_mesh(stage, "/World/AreaLight", light.vertices, light.faces)
    # USD's texture origin is the image's bottom-left corner: t = 1 - v
    st = np.stack([light.uv[:, 0], 1.0 - light.uv[:, 1]], -1).astype(np.float32)
    UsdGeom.PrimvarsAPI(mesh).CreatePrimvar("st", Sdf.ValueTypeNames.TexCoord2fArray,
                                            UsdGeom.Tokens.vertex).Set(Vt.Vec2fArray.FromNumpy(st))
    mat = UsdShade.Material.Define(stage, "/World/Looks/AreaLightMaterial")
    surf = UsdShade.Shader.Define(stage, "/World/Looks/AreaLightMaterial/Surface")
    surf.CreateIdAttr("UsdPreviewSurface")
    surf.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f).Set(Gf.Vec3f(0, 0, 0))
    surf.CreateInput("roughness", Sdf.ValueTypeNames.Float).Set(1.0)
    reader = UsdShade.Shader.Define(stage, "/World/Looks/AreaLightMaterial/StReader")
    reader.CreateIdAttr("UsdPrimvarReader_float2")
    reader.CreateInput("varname", Sdf.ValueTypeNames.String).Set("st")
    tex = UsdShade.Shader.Define(stage, "/World/Looks/AreaLightMaterial/Radiance")
    tex.CreateIdAttr("UsdUVTexture")
    tex.CreateInput("file", Sdf.ValueTypeNames.Asset).Set(files["radiance"].name)
    tex.CreateInput("sourceColorSpace", Sdf.ValueTypeNames.Token).Set("raw")
    tex.CreateInput("wrapS", Sdf.ValueTypeNames.Token).Set("repeat")
    tex.CreateInput("wrapT", Sdf.ValueTypeNames.Token).Set("clamp")
    tex.CreateInput("st", Sdf.ValueTypeNames.Float2).ConnectToSource(reader.ConnectableAPI(), "result")
    tex.CreateOutput("rgb", Sdf.ValueTypeNames.Float3)
    surf.CreateInput("emissiveColor", Sdf.ValueTypeNames.Color3f).ConnectToSource(tex.ConnectableAPI(), "rgb")
    mat.CreateSurfaceOutput().ConnectToSource(surf.ConnectableAPI(), "surface")
    UsdShade.MaterialBindingAPI.Apply(mesh.GetPrim()).Bind(mat)
    files.update(_usd_photo(stage, light, out))
    world.GetPrim().SetCustomDataByKey("roomlight", json.dumps(_extras(light, files)))
    stage.GetRootLayer().Save()
    return {"scene": out, **files}


#: Horizontal aperture of exported cameras (the 35 mm film width); the focal length follows from fx.
APERTURE = 36.0


def _camera_optics(camera: dict) -> dict:
    """Focal length and apertures (in :data:`APERTURE` units) of an exported photo camera, and the
    principal point's offsets, from its pixel intrinsics."""
    k, w, h = camera["intrinsics"], camera["width"], camera["height"]
    mm = APERTURE / w  # film units per pixel (square pixels)
    return {"focal": k["fx"] * mm, "h_aperture": APERTURE, "v_aperture": h * mm * k["fx"] / k["fy"],
            "h_offset": (w / 2 - k["cx"]) * mm, "v_offset": (k["cy"] - h / 2) * mm}


def _write_backplate(light: LightSource, out: Path) -> dict[str, Path]:
    """The photograph beside the scene: float EXR (the exact linear pixels) and an sRGB PNG."""
    from roomlight.core.io import save_png, write_exr

    b = light.backplate
    paths = {"backplate_exr": out.with_name(f"{out.stem}_backplate.exr"),
             "backplate": out.with_name(f"{out.stem}_backplate.png")}
    write_exr(paths["backplate_exr"], {c: b[..., i] for i, c in enumerate("RGB")}, half=False)
    save_png(paths["backplate"], np.round(linear_to_srgb(b) * 255).astype(np.uint8))
    return paths


def _usd_photo(stage, light: LightSource, out: Path) -> dict[str, Path]:
    """A fit-photo's camera (``/World/Camera``), depth mesh (``/World/Photo/DepthMesh``, marked as a
    shadow catcher) and backplate, when the light came with them."""
    from pxr import Gf, Sdf, UsdGeom, UsdShade, Vt

    files: dict[str, Path] = {}
    if light.camera is not None and "intrinsics" in light.camera:
        cam = UsdGeom.Camera.Define(stage, "/World/Camera")
        o = _camera_optics(light.camera)
        cam.CreateFocalLengthAttr(o["focal"])
        cam.CreateHorizontalApertureAttr(o["h_aperture"])
        cam.CreateVerticalApertureAttr(o["v_aperture"])
        cam.CreateHorizontalApertureOffsetAttr(o["h_offset"])
        cam.CreateVerticalApertureOffsetAttr(o["v_offset"])
        cam.CreateClippingRangeAttr(Gf.Vec2f(0.01, 1000.0))
        # camera frame = roomlight's (x right, y up, looking along -z); USD composes row vectors: p M
        m = np.eye(4)
        m[:3, :3] = np.asarray(light.camera["rotation"]).T
        m[3, :3] = light.camera["origin"]
        cam.AddTransformOp().Set(Gf.Matrix4d(m.tolist()))
        if light.backplate is not None:
            files.update(_write_backplate(light, out))
            cam.GetPrim().SetCustomDataByKey("roomlight:backplate", files["backplate"].name)
            cam.GetPrim().SetCustomDataByKey("roomlight:backplate_exr", files["backplate_exr"].name)
        cam.GetPrim().SetCustomDataByKey("roomlight:resolution", Vt.IntArray([light.camera["width"],
                                                                                light.camera["height"]]))
    for obj in light.objects:
        if obj.material != "shadow_catcher":
            continue
        UsdGeom.Xform.Define(stage, "/World/Photo")
        mesh = _usd_mesh(stage, "/World/Photo/DepthMesh", obj.vertices, obj.faces)
        mesh.GetPrim().SetCustomDataByKey("roomlight:shadow_catcher", True)
        mat = UsdShade.Material.Define(stage, "/World/Looks/ShadowCatcher")
        surf = UsdShade.Shader.Define(stage, "/World/Looks/ShadowCatcher/Surface")
        surf.CreateIdAttr("UsdPreviewSurface")
        surf.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f).Set(Gf.Vec3f(0.5, 0.5, 0.5))
        surf.CreateInput("roughness", Sdf.ValueTypeNames.Float).Set(1.0)
        mat.CreateSurfaceOutput().ConnectToSource(surf.ConnectableAPI(), "surface")
        UsdShade.MaterialBindingAPI.Apply(mesh.GetPrim()).Bind(mat)
    return files


def _write_obj(light: LightSource, out: Path) -> dict[str, Path]:
    files = _write_textures(light, out, png=True)
    mtl = out.with_suffix(".mtl")
    s = emission_strength(light.radiance)
    mtl.write_text(
        "# roomlight 2.5D area light: emission = srgb_to_linear(map_Ke texel) * Ke\n"
        f"# exact float radiance: {files['radiance'].name}\n"
        "newmtl area_light\nKa 0 0 0\nKd 0 0 0\nKs 0 0 0\nillum 0\n"
        f"Ke {s:.9g} {s:.9g} {s:.9g}\nmap_Ke {files['emission'].name}\n")
    st = np.stack([light.uv[:, 0], 1.0 - light.uv[:, 1]], -1)  # OBJ's vt origin is the bottom-left
    f = light.faces.astype(np.int64) + 1
    with open(out, "w") as fh:
        fh.write(f"# roomlight 2.5D area light from {light.source}\n# metres, y up, faces point inward\n"
                 f"mtllib {mtl.name}\no area_light\n")
        np.savetxt(fh, light.vertices, fmt="v %.9g %.9g %.9g")
        np.savetxt(fh, st, fmt="vt %.9g %.9g")
        fh.write("usemtl area_light\n")
        np.savetxt(fh, np.repeat(f, 2, axis=1), fmt="f %d/%d %d/%d %d/%d")
    return {"scene": out, "material": mtl, **files}


def export_light(light: LightSource, out, fmt: str | None = None) -> dict[str, Path]:
    """Write ``light`` to ``out`` as ``fmt`` (default: from the suffix); returns the files written."""
    out = Path(out)
    fmt = (fmt or out.suffix.lstrip(".")).lower()
    fmt = {"usda": "usd", "usdc": "usd", "gltf": "glb"}.get(fmt, fmt)
    if fmt not in FORMATS:
        raise ValueError(f"unknown export format {fmt!r}; choose one of {', '.join(FORMATS)}")
    out.parent.mkdir(parents=True, exist_ok=True)
    return {"glb": _write_glb, "usd": _write_usd, "obj": _write_obj}[fmt](light, out)
