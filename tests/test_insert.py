"""roomlight insert: placement on the photograph's surfaces, differential rendering, files and errors.

The references are independent of the compositing code: inserting nothing must give back the
photograph to float precision (the identity of differential rendering), and a diffuse object in a
room of uniform radiance L must shade at albedo x L (the furnace: every direction it sees has
radiance L, or a surface reflecting it)."""

from __future__ import annotations

import json

import numpy as np
import pytest
import torch
from click.testing import CliRunner

from roomlight.cli.main import cli
from roomlight.errors import RoomlightError
from roomlight.fitting.insert import InsertSpec, insert_objects, load_fitted_photo, parse_material, place_object
from roomlight.fitting.insert.composite import composite_objects, place_objects
from roomlight.fitting.insert.objects import surface_at_pixel

pytestmark = [pytest.mark.usefixtures("one_torch_thread")]


def run(*args):
    return CliRunner().invoke(cli, [str(a) for a in args], catch_exceptions=False)


# ------------------------------------------------------------------------------------- placement
def test_materials_parse_or_fail_with_the_forms():
    assert parse_material("mirror")["type"] == "conductor"
    assert parse_material("diffuse:0.8,0.2,0.1")["reflectance"]["value"] == [0.8, 0.2, 0.1]
    assert parse_material("diffuse:0.5")["reflectance"]["value"] == [0.5, 0.5, 0.5]
    p = parse_material("principled:0.7,0.3,1")
    assert p["type"] == "principled" and p["roughness"] == pytest.approx(0.3)
    for bad in ("velvet", "diffuse:", "diffuse:1,2,3", "diffuse:a,b,c", "principled:0.5,0.5", "diffuse:0.1,0.2"):
        with pytest.raises(RoomlightError, match="material|diffuse|principled"):
            parse_material(bad)


def _plane_points(h=20, w=30, height=-1.0):
    """(h, w, 3) camera-frame points of a floor y = ``height`` seen by a camera pitched down 10 degrees."""
    from roomlight.fitting.photo.camera import PhotoCamera, camera_rotation

    k = PhotoCamera.from_fov(60.0, w, h)
    rays = k.pixel_rays() @ camera_rotation(-10.0, 0.0).T   # room frame
    t = height / rays[..., 1]
    pts = rays * t[..., None]
    pts[t <= 0] = np.nan                                     # above the horizon: no floor
    return pts @ camera_rotation(-10.0, 0.0), camera_rotation(-10.0, 0.0)  # back to the camera frame


def test_an_object_rests_on_the_surface_along_its_normal():
    pts, rot = _plane_points()
    up_cam = rot.T @ np.array([0.0, 1.0, 0.0])
    point, normal = surface_at_pixel(pts, 15, 15)
    np.testing.assert_allclose(normal, up_cam, atol=1e-6)   # the floor's normal is the room's up
    placed = place_object(InsertSpec("sphere", at=(15, 15), scale=0.4, material="mirror"), pts, up_cam)
    heights = (placed.vertices - point) @ normal
    assert heights.min() == pytest.approx(0.0, abs=2e-3)     # touching, a hair above
    assert heights.max() == pytest.approx(0.4, abs=5e-3)     # its size along the normal
    centre = placed.vertices.mean(0)
    # straight above the point: the offset from it is along the normal only
    np.testing.assert_allclose(centre - point - ((centre - point) @ normal) * normal, 0, atol=5e-3)
    with pytest.raises(RoomlightError, match="no depth"):
        surface_at_pixel(pts, 15, 0)                         # above the horizon
    with pytest.raises(RoomlightError, match="outside"):
        surface_at_pixel(pts, 30, 5)


# ------------------------------------------------------------------------------- a fitted photo
@pytest.fixture(scope="module")
def fitted_dir(tmp_path_factory):
    """A fit-photo output folder from a short fit of a tiny rendered photo case."""
    from helpers_photo import bright_wall_room, make_tiny_photo

    root = tmp_path_factory.mktemp("insert")
    rad, depth = bright_wall_room(16)
    make_tiny_photo(root / "case", rad, depth, size=(24, 32), spp=32, key=None)
    out = root / "fit"
    r = run("fit-photo", root / "case", "--out", out, "--preset", "fast", "--iterations", 2, "--spp", 2, "--quiet",
            "--compare", "direct-envmap", "--set", "probe_count=1", "--set", "probe_spp=4",
            "--set", "probe_resolution=16", "--set", "init_samples=2", "--set", "placement_steps=10")
    assert r.exit_code == 0, r.output
    return out


@pytest.mark.mitsuba
def test_inserting_nothing_gives_back_the_photograph(fitted_dir):
    fitted = load_fitted_photo(fitted_dir)
    res = insert_objects(fitted, [], size=32, spp=8)
    assert res.composite.shape == res.photo.shape == (24, 32, 3)
    np.testing.assert_array_equal(res.composite, np.maximum(res.photo, 0))
    assert float(res.coverage.max()) == 0.0 and np.all(res.shadow == 1.0)


@pytest.mark.mitsuba
def test_the_command_writes_the_composite_and_refuses_bad_input_in_one_line(fitted_dir, tmp_path):
    out = tmp_path / "ins" / "composite.png"
    r = run("insert", fitted_dir, "--object", "blob", "--at", "16,20", "--material", "diffuse:0.9,0.2,0.2",
            "--size", "32", "--spp", "8", "--out", out)
    assert r.exit_code == 0, r.output
    for name in ("composite.png", "composite.exr", "object_mask.png", "shadow.png", "insert.json"):
        assert (out.parent / name).is_file(), name
    info = json.loads((out.parent / "insert.json").read_text())
    assert info["light"] == "prior" and len(info["objects"]) == 1 and info["size"] == [24, 32]
    share = info["objects"][0]["unseen_light_share"]       # printed as the percentage insert.json holds
    assert f"object 1 (blob): {min(max(share, 0.0), 1.0):.0%} of its shading from parts of the room" in r.output
    assert ("prior's guess" in r.output) == (share >= 0.5), r.output
    from PIL import Image

    mask = np.asarray(Image.open(out.parent / "object_mask.png"))
    assert mask.max() == 255 and (mask > 0).sum() >= 4     # the object is in the picture
    # the same under a compared light, from a placements file
    places = tmp_path / "objects.json"
    places.write_text(json.dumps([{"object": "sphere", "at": [10, 20], "material": "mirror", "scale": 0.2}]))
    r = run("insert", fitted_dir, "--placements", places, "--light", "direct-envmap", "--size", "32", "--spp", "4",
            "--out", tmp_path / "env" / "c.png")
    assert r.exit_code == 0, r.output
    assert json.loads((tmp_path / "env" / "insert.json").read_text())["light_kind"] == "envmap"
    r = run("insert", fitted_dir, "--placements", places, "--exposure", "-1", "--size", "32", "--spp", "4",
            "--out", tmp_path / "dim" / "c.png")
    assert r.exit_code == 0 and "-1.00 EV" in r.output, r.output
    assert json.loads((tmp_path / "dim" / "insert.json").read_text())["exposure_ev"] == -1.0
    # a known albedo in the photograph sets the level: the fitted object then reflects exactly that
    fitted = load_fitted_photo(fitted_dir)
    label = sorted(fitted.materials)[0]
    fitted_albedo = float(np.mean(fitted.materials[label]["albedo"]))
    r = run("insert", fitted_dir, "--placements", places, "--reference-albedo", f"{label}=0.8", "--size", "32",
            "--spp", "4", "--out", tmp_path / "ref" / "c.png")
    assert r.exit_code == 0, r.output
    info = json.loads((tmp_path / "ref" / "insert.json").read_text())
    assert info["reference_albedo"] == {"label": label, "albedo": 0.8}
    assert info["exposure_ev"] == pytest.approx(np.log2(fitted_albedo / 0.8), abs=1e-9)
    moved = fitted.with_exposure(info["exposure_ev"])
    assert np.mean(moved.materials[label]["albedo"]) == pytest.approx(0.8, rel=1e-6)
    bad_mesh = tmp_path / "broken.obj"
    bad_mesh.write_text("v 0 0 0\nf 1 2 oops\n")
    for args, needle in [(["--at", "100,5"], "outside"), (["--at", "16,-3"], "outside"),
                         (["--object", str(bad_mesh), "--at", "16,20"], "broken.obj"),
                         (["--object", "nothing.ply", "--at", "16,20"], "no such mesh"),
                         (["--at", "16,20", "--material", "velvet"], "material"),
                         (["--light", "oracle", "--at", "16,20"], "no such fitted light"),
                         (["--at", "16,20", "--exposure", "20"], "stops"),
                         (["--at", "16,20", "--reference-albedo", "7=0.5"], "no object 7"),
                         (["--at", "16,20", "--reference-albedo", "1=1.5"], "(0, 1]"),
                         (["--at", "16,20", "--reference-albedo", "white"], "LABEL=ALBEDO"),
                         ([], "nothing to insert")]:
        r = CliRunner().invoke(cli, ["insert", str(fitted_dir), *args, "--out", str(tmp_path / "x.png")])
        assert r.exit_code != 0, args
        assert needle in r.output and "Traceback" not in r.output, (args, r.output)
        assert len(r.output.strip().splitlines()) <= 2, r.output


@pytest.mark.mitsuba
def test_a_diffuse_object_in_a_room_of_uniform_radiance_shades_at_albedo_times_radiance(fitted_dir):
    """The fitted light replaced by a uniform room of radiance L (a white furnace): the inserted
    diffuse sphere's pixels in the composite are albedo x L."""
    fitted = load_fitted_photo(fitted_dir)
    L, albedo = 0.6, 0.5
    h, w = fitted.radiance.shape[:2]
    # The room's surfaces well outside the depth mesh, so the local scene sits inside the light.
    from roomlight.core.examples import example_room
    from roomlight.core.light import Light

    _, room_depth = example_room(h)
    fitted.light = Light(torch.full((h, w, 3), L), room_depth * 3.0, "mesh", fitted.light.frame)
    # A photograph of that room, whose fitted objects are white too: every pixel shows radiance L.
    fitted.case.image = np.full_like(fitted.case.image, L)
    white = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [1.0, 1.0, 1.0]}}
    fitted.bsdfs = lambda: {lab: white for lab in fitted.materials}
    res = insert_objects(fitted, [InsertSpec("sphere", at=(16, 21), scale=0.35, material=f"diffuse:{albedo}")],
                         size=32, spp=512, seed=3)
    inside = res.coverage > 0.99
    assert inside.sum() >= 6, inside.sum()
    shade = res.composite[inside].mean(0)
    np.testing.assert_allclose(shade, albedo * L, rtol=0.05)


def test_exposure_moves_the_light_against_the_objects_albedos_and_refuses_nonsense(fitted_dir):
    fitted = load_fitted_photo(fitted_dir)
    brighter = fitted.with_exposure(1.0)
    assert brighter.exposure_ev == 1.0 and fitted.exposure_ev == 0.0
    np.testing.assert_allclose(brighter.radiance.numpy(), 2.0 * fitted.radiance.numpy(), rtol=1e-6)
    for lab, m in fitted.materials.items():
        np.testing.assert_allclose(brighter.materials[lab]["albedo"], np.asarray(m["albedo"]) / 2.0, rtol=1e-6)
        assert brighter.materials[lab]["roughness"] == m["roughness"]
    darker = fitted.with_exposure(-2.0)           # albedos x4, held at 1
    for lab, m in fitted.materials.items():
        np.testing.assert_allclose(darker.materials[lab]["albedo"], np.minimum(1.0, 4.0 * np.asarray(m["albedo"])),
                                   rtol=1e-6)
    for bad in (float("nan"), 11.0, -40.0):
        with pytest.raises(RoomlightError, match="stops"):
            fitted.with_exposure(bad)


@pytest.mark.mitsuba
def test_a_brighter_reading_brightens_the_new_object_as_path_space_says(fitted_dir):
    """The white furnace of the test above, read with the light 2^EV times as bright. The photograph still
    shows L everywhere, so the local scene's estimated albedo is 1/s (s = 2^EV) and every surface of the
    photograph keeps radiance L. A path from the camera to the new object and on to the light picks up the
    light's s once and 1/s at each bounce on the photograph's surfaces, and with one seed every EV traces
    the same paths (cosine sampling does not look at albedos, and the path is shorter than Russian
    roulette's start), so the object's radiance is r(s) = A s + B + C / s + ..., A the light it sees
    directly. Fitted on s = 2, 4, 8, that law predicts s = 16; and A s is a share of r between 0 and 1."""
    from roomlight.core.examples import example_room
    from roomlight.core.light import Light

    base = load_fitted_photo(fitted_dir)
    L, albedo = 0.6, 0.5
    h, w = base.radiance.shape[:2]
    _, room_depth = example_room(h)
    base.light = Light(torch.full((h, w, 3), L), room_depth * 3.0, "mesh", base.light.frame)
    base.case.image = np.full_like(base.case.image, L)
    base.materials = {lab: {**m, "albedo": [1.0, 1.0, 1.0]} for lab in base.materials for m in [base.materials[lab]]}
    spec = [InsertSpec("sphere", at=(16, 21), scale=0.35, material=f"diffuse:{albedo}")]
    shade = {}
    for ev in (1, 2, 3, 4):
        moved = base.with_exposure(ev)
        # the fitted objects as Lambertian surfaces of their (moved) albedo, as in the furnace above
        moved.bsdfs = lambda m=moved: {lab: {"type": "diffuse", "reflectance": {"type": "rgb", "value": v["albedo"]}}
                                       for lab, v in m.materials.items()}
        res = insert_objects(moved, spec, size=32, spp=256, seed=3, unseen_share=False)
        assert res.info["exposure_ev"] == ev
        # the photograph's own reading is kept: its surfaces read as albedo 1/s and still render at L
        # (medians: a few pixels at depth edges see the light itself, at s L, in both renders alike)
        objects = resize_labels(base.case, res.without_objects.shape[:2]) > 0
        np.testing.assert_allclose(np.median(res.albedo[~objects]), 2.0 ** -ev, rtol=0.06)
        np.testing.assert_allclose(np.median(res.without_objects[~objects]), L, rtol=0.06)
        inside = res.coverage > 0.99
        assert inside.sum() >= 6, inside.sum()
        shade[2.0 ** ev] = float(res.composite[inside].mean())
    s = np.array([2.0, 4.0, 8.0])
    A, B, C = np.linalg.solve(np.stack([s, np.ones(3), 1.0 / s], 1), [shade[x] for x in s])
    assert shade[16.0] == pytest.approx(16 * A + B + C / 16, rel=0.03), (shade, A, B, C)
    assert A > 0 and 0.1 < 2 * A / shade[2.0] < 1.0, (A, shade)
    assert shade[16.0] > 4 * shade[2.0]             # most of its light comes straight from the room


def resize_labels(case, shape):
    """The photograph's object labels at ``shape`` (nearest pixel)."""
    h, w = shape
    ii = (np.arange(h) + 0.5) * case.height / h
    jj = (np.arange(w) + 0.5) * case.width / w
    return np.asarray(case.objects.labels)[ii.astype(int)[:, None], jj.astype(int)[None, :]]


@pytest.mark.mitsuba
def test_a_light_running_through_the_photographed_scene_is_pushed_behind_it(fitted_dir):
    """The white furnace again, with the light's surface at half the scene's distance: the depth mesh and
    the object stand outside the light, where its back faces emit nothing. Pushed out behind them
    (roomlight.core.emitter.enclose) the object shades at albedo x L again; left in place it does not."""
    from roomlight.core.examples import example_room
    from roomlight.core.light import Light

    fitted = load_fitted_photo(fitted_dir)
    L, albedo = 0.6, 0.5
    h, w = fitted.radiance.shape[:2]
    _, room_depth = example_room(h)
    scene_far = float(np.nanmax(fitted.case.depth)) * fitted.transform.scale
    fitted.light = Light(torch.full((h, w, 3), L), room_depth / room_depth.max() * 0.5 * scene_far, "mesh",
                         fitted.light.frame)
    fitted.case.image = np.full_like(fitted.case.image, L)
    white = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [1.0, 1.0, 1.0]}}
    fitted.bsdfs = lambda: {lab: white for lab in fitted.materials}
    spec = [InsertSpec("sphere", at=(16, 21), scale=0.35, material=f"diffuse:{albedo}")]
    fixed = insert_objects(fitted, spec, size=32, spp=512, seed=3, unseen_share=False)
    inside = fixed.coverage > 0.99
    assert inside.sum() >= 6, inside.sum()
    np.testing.assert_allclose(fixed.composite[inside].mean(0), albedo * L, rtol=0.05)
    moved = fixed.info["light_enclosing_scene"]
    assert moved["on"] is True and moved["texels_moved"] > 0.05
    placed = place_objects(fitted, spec)
    broken = composite_objects(fitted, placed, size=32, spp=512, seed=3, enclose=False)
    assert abs(float(broken.composite[inside].mean()) / (albedo * L) - 1.0) > 0.2


# ------------------------------------------------------------------------ out to other tools
@pytest.mark.mitsuba
def test_export_of_a_photo_fit_carries_the_camera_the_depth_mesh_and_the_backplate(fitted_dir, tmp_path):
    pytest.importorskip("pxr")
    pytest.importorskip("pygltflib")
    r = run("export", fitted_dir, "--format", "usd")
    assert r.exit_code == 0, r.output
    usd = fitted_dir / "export" / "light.usda"
    for name in ("light.usda", "light_radiance.exr", "light_backplate.png", "light_backplate.exr", "light_blender.py"):
        assert (fitted_dir / "export" / name).is_file(), name
    from pxr import Usd, UsdGeom

    from roomlight.fitting.insert import load_fitted_photo

    fitted = load_fitted_photo(fitted_dir)
    stage = Usd.Stage.Open(str(usd))
    cam = UsdGeom.Camera(stage.GetPrimAtPath("/World/Camera"))
    # the horizontal field of view and the pose of the photograph's camera
    fov = 2 * np.degrees(np.arctan(cam.GetHorizontalApertureAttr().Get() / (2 * cam.GetFocalLengthAttr().Get())))
    assert fov == pytest.approx(fitted.case.intrinsics.fov_x, rel=1e-6)
    m = np.array(UsdGeom.Xformable(cam).ComputeLocalToWorldTransform(Usd.TimeCode.Default()))
    np.testing.assert_allclose(m[3, :3], fitted.transform.translation, atol=1e-6)
    np.testing.assert_allclose(m[:3, :3].T, fitted.transform.rotation, atol=1e-6)
    depth = stage.GetPrimAtPath("/World/Photo/DepthMesh")
    assert depth and depth.GetCustomDataByKey("roomlight:shadow_catcher") is True
    pts = np.array(UsdGeom.Mesh(depth).GetPointsAttr().Get())
    # the depth mesh's points are the photograph's pixels, seen by that camera in the room frame
    seen = (pts - fitted.transform.translation) @ fitted.transform.rotation   # back to the camera frame
    assert (seen[:, 2] < 0).all()
    import pygltflib

    out = tmp_path / "photo.glb"
    assert run("export", fitted_dir, "--out", out).exit_code == 0
    g = pygltflib.GLTF2().load(str(out))
    names = [n.name for n in g.nodes]
    assert {"area_light", "depth_mesh", "photo_camera"} <= set(names)
    cam_node = g.nodes[names.index("photo_camera")]
    yfov = g.cameras[cam_node.camera].perspective.yfov
    k = fitted.case.intrinsics
    assert yfov == pytest.approx(2 * np.arctan(k.height / (2 * k.fy)), rel=1e-6)
    assert cam_node.extras["roomlight"]["backplate"] == "photo_backplate.png"
    x, y, z, w = cam_node.rotation                      # glTF: (x, y, z, w), camera to world
    rot = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                    [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                    [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
    np.testing.assert_allclose(rot, fitted.transform.rotation, atol=1e-6)
    np.testing.assert_allclose(cam_node.translation, fitted.transform.translation, atol=1e-6)


@pytest.mark.mitsuba
def test_export_moves_the_lights_level_as_insert_does(fitted_dir, tmp_path):
    """--exposure and --reference-albedo scale the exported light's float radiance by exactly the factor
    insert renders with, and the file records the stops; a folder that is no photo fit is refused."""
    pytest.importorskip("pygltflib")
    import pygltflib

    from roomlight.core.io import read_exr
    from roomlight.fitting.insert import load_fitted_photo

    def radiance(path):
        ch = read_exr(path)
        return np.stack([ch[c] for c in "RGB"], -1)

    assert run("export", fitted_dir, "--out", tmp_path / "as" / "l.glb").exit_code == 0
    r = run("export", fitted_dir, "--out", tmp_path / "dim" / "l.glb", "--exposure", "-1.5")
    assert r.exit_code == 0 and "-1.50 EV" in r.output, r.output
    base = radiance(tmp_path / "as" / "l_radiance.exr")
    np.testing.assert_allclose(radiance(tmp_path / "dim" / "l_radiance.exr"), base * 2.0 ** -1.5, rtol=1e-6)
    extras = pygltflib.GLTF2().load(str(tmp_path / "dim" / "l.glb")).extras
    assert "exposure_ev" not in pygltflib.GLTF2().load(str(tmp_path / "as" / "l.glb")).extras["roomlight"]
    assert extras["roomlight"]["exposure_ev"] == -1.5
    fitted = load_fitted_photo(fitted_dir)
    label = sorted(fitted.materials)[0]
    gain = 0.5 / float(np.mean(fitted.materials[label]["albedo"]))     # the light's factor for albedo 0.5
    r = run("export", fitted_dir, "--out", tmp_path / "ref" / "l.glb", "--reference-albedo", f"{label}=0.5")
    assert r.exit_code == 0, r.output
    np.testing.assert_allclose(radiance(tmp_path / "ref" / "l_radiance.exr"), base / gain, rtol=1e-5)
    bundle = fitted_dir / "emitter"
    for args, needle in [([bundle, "--reference-albedo", "1=0.5"], "fit-photo"),
                         ([fitted_dir, "--reference-albedo", "x"], "LABEL=ALBEDO"),
                         ([fitted_dir, "--exposure", "11"], "stops")]:
        r = CliRunner().invoke(cli, ["export", *map(str, args), "--out", str(tmp_path / "bad.glb")])
        assert r.exit_code != 0 and needle in r.output and "Traceback" not in r.output, (args, r.output)


# ----------------------------------------------------------------------------- in the viewer
@pytest.mark.slow
@pytest.mark.mitsuba
def test_viewer_of_a_photo_fit_shows_the_photograph_and_the_probe_shading_follows_the_surface(fitted_dir, tmp_path):
    """The photograph is the backdrop; a probe dropped on two surface points of the photograph is
    shaded differently under the 2.5D light (left inset) and identically under the env map (right)."""
    from helpers_browser import screenshot

    pytest.importorskip("PIL")
    try:
        from roomlight.viewer.three import three_dir

        three_dir()
    except Exception as exc:  # three.js missing: the viewer cannot be written
        pytest.skip(f"three.js is not installed: {exc}")
    page = tmp_path / "photo.html"
    r = run("view", fitted_dir, "--out", page, "--cube-size", "64")
    assert r.exit_code == 0, r.output
    size = (900, 500)
    left, right, top, iw, ih = 900 - 2 * 248, 900 - 248, 8, 240, 120
    a = screenshot(page, tmp_path / "a.png", "at=0.25,0.85&material=diffuse", size, budget_ms=300).astype(float)
    b = screenshot(page, tmp_path / "b.png", "at=0.8,0.5&material=diffuse", size, budget_ms=300).astype(float)

    def region(img, x, y, w, h):
        return img[y:y + h, x:x + w]

    assert np.abs(region(a, left, top, iw, ih) - region(b, left, top, iw, ih)).mean() > 1.0, \
        "the probe's shading under the 2.5D light must change with where it rests"
    np.testing.assert_allclose(region(a, right, top, iw, ih), region(b, right, top, iw, ih), atol=1,
                               err_msg="under the env map the probe's shading does not depend on its position")
    # the backdrop: the main view (letterboxed to 4:3 in the 900 x 500 window) shows the photograph
    from roomlight.core.color import linear_to_srgb

    photo = np.rint(linear_to_srgb(np.clip(load_fitted_photo(fitted_dir).case.image, 0, 1)) * 255)
    vh, vw = 500, round(500 * 32 / 24)
    x0 = (900 - vw) // 2
    bottom = a[int(0.9 * vh):vh - 2, x0 + vw // 2:x0 + vw - 2]   # right part of the floor, away from the probe
    ref = photo[int(0.9 * 24):, 16:].reshape(-1, 3).mean(0)
    np.testing.assert_allclose(bottom.reshape(-1, 3).mean(0), ref, atol=25)


def test_seen_texels_are_the_directions_inside_the_camera_s_frustum():
    """A light at infinity seen by a camera at the origin looking down -z, no tilt: a texel is seen exactly
    when its direction's horizontal and vertical angles off the axis are inside half the fields of view."""
    import math
    from types import SimpleNamespace

    from roomlight.core.geometry.equirect import pixel_directions
    from roomlight.fitting.insert.composite import seen_texels
    from roomlight.fitting.photo.camera import PhotoCamera
    from roomlight.fitting.photo.geometry import SceneTransform

    h, w = 48, 96
    cam = PhotoCamera.from_fov(70.0, 64, 48)
    t = SceneTransform(np.eye(3), 1.0, np.zeros(3))
    fitted = SimpleNamespace(radiance=torch.ones(h, w, 3), depth=None, transform=t)
    seen = seen_texels(fitted, cam)
    d = pixel_directions(h, w, dtype=torch.float64).numpy()
    half_x = math.atan(cam.width / 2 / cam.fx)
    half_y = math.atan(cam.height / 2 / cam.fy)
    ahead = d[..., 2] < 0
    ax = np.arctan2(np.abs(d[..., 0]), -d[..., 2])
    ay = np.arctan2(np.abs(d[..., 1]), -d[..., 2])
    expected = ahead & (ax <= half_x) & (ay <= half_y)
    assert seen.sum() > 20 and np.array_equal(seen, expected)
    # a 2.5D light: what is seen depends on the camera's position inside it. A camera 1 m behind the
    # centre of a room of radius 2 sees more of the room ahead than one at the centre.
    behind = SceneTransform(np.eye(3), 1.0, np.array([0.0, 0.0, 1.0]))
    mesh = SimpleNamespace(radiance=torch.ones(h, w, 3), depth=torch.full((h, w), 2.0), transform=behind)
    assert seen_texels(mesh, cam).sum() > seen.sum()


@pytest.mark.mitsuba
def test_the_unseen_share_is_one_under_unseen_light_only_and_falls_as_the_seen_light_grows(fitted_dir):
    """Under a light that is dark wherever the photograph looks, all of an object's shading is from unseen
    parts: exactly 1. Brightening only the seen texels of a uniform light lowers the share."""
    from roomlight.core.light import Light
    from roomlight.fitting.insert.composite import seen_texels

    fitted = load_fitted_photo(fitted_dir)
    seen = torch.from_numpy(seen_texels(fitted, fitted.case.intrinsics.scaled(32, 24)))
    assert 0 < int(seen.sum()) < seen.numel()
    spec = [InsertSpec("sphere", at=(16, 21), scale=0.35, material="diffuse:0.6")]
    h, w = fitted.radiance.shape[:2]
    shares = {}
    for name, radiance in (("unseen only", torch.where(seen[..., None], 0.0, 0.5).expand(h, w, 3)),
                           ("uniform", torch.full((h, w, 3), 0.5)),
                           ("seen x4", torch.where(seen[..., None], 2.0, 0.5).expand(h, w, 3))):
        fitted.light = Light(radiance.contiguous(), fitted.depth, fitted.kind, fitted.light.frame)
        info = insert_objects(fitted, spec, size=32, spp=64, seed=2).info
        shares[name] = info["objects"][0]["unseen_light_share"]
    assert shares["unseen only"] == 1.0
    assert 0.0 < shares["seen x4"] < shares["uniform"] < 1.0, shares


@pytest.mark.mitsuba
def test_a_given_albedo_replaces_the_estimate_and_what_the_object_changes_scales_with_it(fitted_dir):
    """The local scene's albedo passed in (the diagnosis's true albedo) is used as it is: given the estimate
    itself the composite is the same bit for bit; what the object changes around it (its shadow, light it
    throws) is a reflection off the local scene, so it doubles with the albedo (to first order: a little
    more through the second bounce)."""
    fitted = load_fitted_photo(fitted_dir)
    placed = place_objects(fitted, [InsertSpec("sphere", at=(16, 21), scale=0.35, material="diffuse:0.5")])
    base = composite_objects(fitted, placed, size=32, spp=16, seed=3)
    again = composite_objects(fitted, placed, size=32, spp=16, seed=3, albedo=base.albedo)
    np.testing.assert_array_equal(again.composite, base.composite)
    change = {}
    for a in (0.1, 0.2):
        res = composite_objects(fitted, placed, size=32, spp=16, seed=3, albedo=np.full_like(base.albedo, a))
        outside = res.coverage == 0
        change[a] = float((res.composite - res.photo)[outside].sum())
    assert abs(change[0.1]) > 1e-3
    assert 1.9 < change[0.2] / change[0.1] < 2.4, change
    with pytest.raises(Exception, match="albedo"):
        composite_objects(fitted, placed, size=32, spp=4, albedo=np.zeros((3, 3, 3)))


@pytest.mark.mitsuba
def test_a_given_local_geometry_equal_to_the_depth_mesh_reproduces_the_composite(fitted_dir):
    """The local scene's shape can be given instead of the depth mesh (to measure what its shape costs);
    given the depth mesh itself, with its own texture coordinates and objects, the composite is the same
    image: the given shape goes through the same lighting, enclosing and albedo estimate."""
    from roomlight.fitting.insert.composite import LocalGeometry
    from roomlight.fitting.photo.geometry import build_geometry, working_size
    from roomlight.fitting.photo.masks import resize_nearest

    fitted = load_fitted_photo(fitted_dir)
    placed = place_objects(fitted, [InsertSpec("sphere", at=(16, 21), scale=0.35, material="diffuse:0.5")])
    base = composite_objects(fitted, placed, size=32, spp=16, seed=3)
    case, cfg = fitted.case, fitted.config
    geo = build_geometry(case, cfg)
    gh, gw = working_size(case.height, case.width, cfg.geometry_size)
    labels = resize_nearest(case.objects.labels, gh, gw).reshape(-1)
    faces = geo.mesh.faces[~np.isin(labels, [o.label for o in geo.objects])[geo.mesh.faces].any(1)]
    ii, jj = np.meshgrid(np.arange(gh), np.arange(gw), indexing="ij")
    uv = np.stack([(jj.ravel() + 0.5) / gw, (ii.ravel() + 0.5) / gh], 1)
    given = LocalGeometry(geo.mesh.vertices, faces, uv, {o.label: (o.vertices, o.faces, o.normals) for o in geo.objects})
    again = composite_objects(fitted, placed, size=32, spp=16, seed=3, geometry=given)
    np.testing.assert_array_equal(again.albedo, base.albedo)
    np.testing.assert_array_equal(again.composite, base.composite)
    # Without its objects the shape differs, and so does the composite.
    bare = composite_objects(fitted, placed, size=32, spp=16, seed=3,
                             geometry=LocalGeometry(geo.mesh.vertices, faces, uv, {}))
    assert np.abs(bare.composite - base.composite).max() > 1e-3
