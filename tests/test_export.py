"""``roomlight export``: each format read back by a maintained library and compared to the bundle.

The references are the bundle's own files (``emitter.ply`` read by roomlight's PLY reader, which
test_io_files checks against Mitsuba; ``radiance.exr`` read with OpenEXR directly), the glTF
binary layout read by hand from the GLB header, and the sRGB transfer function from IEC 61966-2-1.
"""

from __future__ import annotations

import json
import struct

import numpy as np
import pytest
from click.testing import CliRunner

from roomlight.cli.main import cli
from roomlight.core.emitter.export import export_emitter
from roomlight.core.examples import example_room
from roomlight.core.io import read_ply

trimesh = pytest.importorskip("trimesh")


def _srgb_to_linear(c):
    c = np.asarray(c, np.float64) / 255.0
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def _exr_rgb(path):
    import OpenEXR

    with OpenEXR.File(str(path)) as f:
        ch = f.channels()
        if "RGB" in ch:  # OpenEXR >= 3.3 groups R, G, B into one channel by default
            return np.asarray(ch["RGB"].pixels, np.float64)
        return np.stack([ch[c].pixels for c in "RGB"], -1).astype(np.float64)


@pytest.fixture(scope="module")
def bundle(tmp_path_factory):
    rad, depth = example_room(8)
    out = tmp_path_factory.mktemp("bundle") / "emitter"
    export_emitter(out, rad, depth, "mesh")
    ply = read_ply(out / "emitter.ply")
    return out, ply, _exr_rgb(out / "radiance.exr")


def _export(bundle, tmp_path, name, *extra):
    out = tmp_path / name
    res = CliRunner().invoke(cli, ["export", str(bundle[0]), "--out", str(out), *extra])
    assert res.exit_code == 0, res.output
    return out


def _check_texture(texel_rgb, strength, radiance):
    """8-bit sRGB texels times the strength give the radiance to within half a code value."""
    assert texel_rgb.shape == radiance.shape
    back = _srgb_to_linear(texel_rgb) * strength
    # d(linear)/d(code) <= 2.4/1.055/255 at the top of the range: half a code is at most 0.45 % of s
    assert np.abs(back - radiance).max() <= 0.0045 * strength
    assert strength == pytest.approx(radiance.max(), rel=1e-6)


def _glb_json(path):
    data = path.read_bytes()
    magic, version, length = struct.unpack_from("<4sII", data, 0)
    assert (magic, version, length) == (b"glTF", 2, len(data))
    chunk_len, chunk_type = struct.unpack_from("<I4s", data, 12)
    assert chunk_type == b"JSON"
    return json.loads(data[20:20 + chunk_len])


def test_glb_round_trip(bundle, tmp_path):
    out = _export(bundle, tmp_path, "light.glb")
    _, ply, radiance = bundle
    doc = _glb_json(out)
    assert "KHR_materials_emissive_strength" in doc["extensionsUsed"]
    mat = doc["materials"][0]
    strength = mat["extensions"]["KHR_materials_emissive_strength"]["emissiveStrength"]
    assert mat["emissiveFactor"] == [1.0, 1.0, 1.0] and mat["doubleSided"] is True
    assert doc["samplers"][0]["wrapS"] == 10497 and doc["samplers"][0]["wrapT"] == 33071  # REPEAT, CLAMP

    scene = trimesh.load(out, process=False)
    (mesh,) = scene.geometry.values()
    np.testing.assert_allclose(mesh.vertices, ply["vertices"], atol=1e-6)
    np.testing.assert_array_equal(mesh.faces, ply["faces"])
    # trimesh turns glTF's top-left texture origin into its bottom-left one on loading
    np.testing.assert_allclose(mesh.visual.uv, np.stack([ply["uv"][:, 0], 1 - ply["uv"][:, 1]], -1), atol=1e-6)
    texture = np.asarray(mesh.visual.material.emissiveTexture.convert("RGB"))
    _check_texture(texture, strength, radiance)
    assert (out.parent / "light_radiance.exr").is_file()
    np.testing.assert_array_equal(_exr_rgb(out.parent / "light_radiance.exr"), radiance)


def test_usd_round_trip(bundle, tmp_path):
    pxr = pytest.importorskip("pxr")
    from pxr import Usd, UsdGeom, UsdShade

    out = _export(bundle, tmp_path, "light.usda")
    _, ply, radiance = bundle
    stage = Usd.Stage.Open(str(out))
    assert UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.y and UsdGeom.GetStageMetersPerUnit(stage) == 1.0
    mesh = UsdGeom.Mesh(stage.GetPrimAtPath("/World/AreaLight"))
    np.testing.assert_allclose(np.array(mesh.GetPointsAttr().Get()), ply["vertices"], atol=1e-6)
    np.testing.assert_array_equal(np.array(mesh.GetFaceVertexIndicesAttr().Get()).reshape(-1, 3), ply["faces"])
    assert set(mesh.GetFaceVertexCountsAttr().Get()) == {3}
    st = np.array(UsdGeom.PrimvarsAPI(mesh).GetPrimvar("st").Get())
    np.testing.assert_allclose(st, np.stack([ply["uv"][:, 0], 1 - ply["uv"][:, 1]], -1), atol=1e-6)  # t up
    material, _ = UsdShade.MaterialBindingAPI(mesh.GetPrim()).ComputeBoundMaterial()
    surface = material.ComputeSurfaceSource()[0]
    assert surface.GetIdAttr().Get() == "UsdPreviewSurface"
    source = surface.GetInput("emissiveColor").GetConnectedSources()[0][0].source
    tex = UsdShade.Shader(source.GetPrim())
    assert tex.GetIdAttr().Get() == "UsdUVTexture"
    assert tex.GetInput("sourceColorSpace").Get() == "raw"
    path = out.parent / tex.GetInput("file").Get().path
    np.testing.assert_array_equal(_exr_rgb(path), radiance)
    if hasattr(pxr, "UsdValidation"):  # USD's own validators (usd-core >= 24.11)
        from pxr import UsdValidation

        ctx = UsdValidation.ValidationContext(UsdValidation.ValidationRegistry().GetOrLoadAllValidators())
        assert [e.GetErrorAsString() for e in ctx.Validate(stage)] == []


def test_obj_round_trip(bundle, tmp_path):
    out = _export(bundle, tmp_path, "light.obj")
    _, ply, radiance = bundle
    mesh = trimesh.load(out, process=False, maintain_order=True)
    np.testing.assert_allclose(mesh.vertices, ply["vertices"], atol=1e-6)
    np.testing.assert_array_equal(mesh.faces, ply["faces"])
    np.testing.assert_allclose(mesh.visual.uv, np.stack([ply["uv"][:, 0], 1 - ply["uv"][:, 1]], -1), atol=1e-6)
    mtl = dict(line.split(" ", 1) for line in out.with_suffix(".mtl").read_text().splitlines()
               if line and not line.startswith("#"))
    ke = [float(x) for x in mtl["Ke"].split()]
    assert ke[0] == ke[1] == ke[2]
    from PIL import Image

    texture = np.asarray(Image.open(out.parent / mtl["map_Ke"].strip()).convert("RGB"))
    _check_texture(texture, ke[0], radiance)


def test_export_needs_a_known_format(bundle, tmp_path):
    res = CliRunner().invoke(cli, ["export", str(bundle[0]), "--out", str(tmp_path / "light.fbx")])
    assert res.exit_code != 0 and "--format" in res.output


def test_export_of_a_folder_without_a_light_names_what_it_expected(tmp_path):
    res = CliRunner().invoke(cli, ["export", str(tmp_path), "--out", str(tmp_path / "x.glb")])
    assert res.exit_code == 2 and "no emitter here" in res.output and "scene.json" in res.output


def test_load_light_finds_the_light_behind_each_kind_of_output(tmp_path):
    """Samples, fits, env-map bundles with depth, scene files: the same mesh as the bundle's PLY."""
    import json as _json

    from roomlight.export import load_light
    from roomlight.core.io import write_panorama

    rad, depth = example_room(8)
    export_emitter(tmp_path / "samples" / "sample_000", rad, depth, "mesh")
    export_emitter(tmp_path / "fit" / "emitter", rad, depth, "mesh")
    export_emitter(tmp_path / "env", rad, depth, "envmap")
    reference = read_ply(tmp_path / "fit" / "emitter" / "emitter.ply")
    (tmp_path / "case").mkdir()
    write_panorama(tmp_path / "case" / "emitter.exr", (rad.numpy(), depth.numpy()), half=False)
    (tmp_path / "case" / "scene.json").write_text(_json.dumps({
        "version": 1, "emitter": {"panorama": "emitter.exr"},
        "objects": [{"id": "ball", "shape": "sphere", "scale": 0.25, "translate": [0.5, -0.5, -1.0]}],
        "views": {"input": {"camera": {"origin": [0, 0, 0], "target": [0, 0, -1], "width": 32, "height": 32}, "objects": ["ball"]}}}))
    for path in ("samples", "samples/sample_000", "fit", "env", "case", "case/scene.json"):
        light = load_light(tmp_path / path)
        np.testing.assert_allclose(light.vertices, reference["vertices"], atol=1e-5, err_msg=path)
        np.testing.assert_array_equal(light.faces, reference["faces"])
        np.testing.assert_allclose(light.uv, reference["uv"], atol=1e-7)
        np.testing.assert_allclose(light.radiance, rad.numpy(), rtol=1e-6)
    (ball,) = light.objects
    # the built-in sphere has bounding radius 1: scale 0.25 around the translation
    np.testing.assert_allclose(ball.vertices.min(0), [0.25, -0.75, -1.25], atol=1e-3)
    np.testing.assert_allclose(ball.vertices.max(0), [0.75, -0.25, -0.75], atol=1e-3)
    assert ball.role == "input" and light.camera["target"] == [0.0, 0.0, -1.0]
