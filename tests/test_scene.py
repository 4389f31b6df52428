"""The scene description: round trips, validation messages, unreadable files, the materials' BSDFs against
their reflectance models, built-in shapes."""

import copy
import json
import math

import numpy as np
import pytest

from roomlight.core.examples import example_room
from roomlight.core.io import save_png, write_exr, write_panorama, write_ply
from roomlight.fitting.scene import (
    BUILTIN_SHAPES,
    SceneError,
    builtin_shape,
    load_scene,
    save_scene,
)
from roomlight.fitting.scene.description import MATERIAL_TYPES, ObjectSpec, parse_scene

from helpers_bsdf import (conductor_f0, direction, fresnel_conductor, fresnel_dielectric, microfacet_reflection,
                          principled, reflect, rough_interface)


# ------------------------------------------------------------------------------- fixtures
@pytest.fixture
def scene_dir(tmp_path):
    """A folder with every kind of file a scene refers to, and a valid scene mapping for it."""
    rad, depth = example_room(8)
    write_panorama(tmp_path / "room.exr", (rad.numpy(), depth.numpy()))
    write_exr(tmp_path / "depth.exr", {"Z": depth.numpy()})
    v, f = builtin_shape("torus")
    (tmp_path / "meshes").mkdir()
    write_ply(tmp_path / "meshes" / "torus.ply", v, f)
    img = np.full((6, 8, 3), 0.25, np.float32)
    write_exr(tmp_path / "input.exr", {c: img[..., k] for k, c in enumerate("RGB")})
    save_png(tmp_path / "input.png", np.full((6, 8, 3), 128, np.uint8))
    save_png(tmp_path / "mask.png", np.full((6, 8), 255, np.uint8))
    data = {
        "version": 1,
        "objects": [
            {"id": "a", "shape": "knot", "translate": [0.1, -0.2, -1.5], "scale": 0.3, "rotate": [0, 1, 0, 30],
             "material": {"type": "diffuse", "reflectance": [0.5, 0.4, 0.3]}},
            {"id": "b", "mesh": "meshes/torus.ply", "material": {"type": "matte", "alpha": 0.3}},
            {"id": "c", "shape": "sphere", "material": "mirror"},
            {"id": "d", "shape": "blob", "material": {"type": "principled", "base_color": [0.2, 0.3, 0.4],
                                                     "roughness": 0.4, "metallic": 1.0}},
        ],
        "views": {
            "input": {"camera": {"origin": [0, 0, 0], "target": [0, 0, -1], "up": [0, 1, 0], "fov": 65,
                                 "width": 8, "height": 6},
                      "objects": ["a", "b", "d"], "image": "input.exr", "ldr": "input.png", "mask": "mask.png"},
            "eval": {"camera": {"fov": 50, "width": 8, "height": 6}, "objects": ["c"]},
        },
        "emitter": {"panorama": "room.exr", "depth": "depth.exr"},
        "metadata": {"note": "test"},
    }
    return tmp_path, data


def _write(tmp_path, data, name="scene.json"):
    p = tmp_path / name
    if name.endswith((".yaml", ".yml")):
        import yaml

        p.write_text(yaml.safe_dump(data))
    else:
        p.write_text(json.dumps(data))
    return p


# ------------------------------------------------------------------------------- round trips
@pytest.mark.parametrize("name", ["scene.json", "scene.yaml"])
def test_round_trip_save_load(scene_dir, name):
    root, data = scene_dir
    s1 = load_scene(_write(root, data, name))
    assert set(s1.objects) == {"a", "b", "c", "d"}
    assert s1.objects["b"].mesh == (root / "meshes" / "torus.ply").resolve()
    assert s1.objects["c"].material.type == "mirror"
    assert s1.views["input"].camera.height == 6 and s1.views["eval"].camera.fov == 50
    assert s1.emitter.depth == (root / "depth.exr").resolve()
    out = root / ("again" + name[5:])
    save_scene(s1, out)
    text = out.read_text()
    assert str(root) not in text  # paths are written relative to the scene file
    s2 = load_scene(out)
    assert s2.to_dict() == s1.to_dict()
    assert s1.to_dict()["objects"][1]["mesh"] == "meshes/torus.ply"


def test_load_scene_accepts_directory(scene_dir):
    root, data = scene_dir
    _write(root, data)
    assert set(load_scene(root).views) == {"input", "eval"}


def test_defaults_are_filled(scene_dir):
    root, data = scene_dir
    d = copy.deepcopy(data)
    d["objects"] = [{"id": "x", "shape": "cup"}]
    d["views"] = {"v": {"camera": {"width": 4, "height": 4}, "objects": ["x"]}}
    del d["emitter"]
    s = parse_scene(d, root)
    o = s.objects["x"]
    assert o.material.type == "diffuse" and o.scale == 1.0 and o.translate == (0.0, 0.0, 0.0)
    cam = s.views["v"].camera
    assert cam.fov == 65.0 and cam.target == (0.0, 0.0, -1.0) and cam.up == (0.0, 1.0, 0.0)
    assert s.emitter is None


def test_object_transform_is_scale_rotate_translate():
    from roomlight.fitting.scene.build import object_geometry

    o = ObjectSpec("o", shape="spiky", translate=(1.0, 2.0, 3.0), scale=0.5, rotate=(0.0, 1.0, 0.0, 90.0))
    v, f = object_geometry(o)
    v0, f0 = builtin_shape("spiky")
    # A right-handed quarter turn about +y maps x -> -z and z -> x.
    expect = 0.5 * np.stack([v0[:, 2], v0[:, 1], -v0[:, 0]], 1) + [1.0, 2.0, 3.0]
    np.testing.assert_allclose(v, expect, atol=1e-6)
    np.testing.assert_array_equal(f, f0)


# ------------------------------------------------------------------------------- materials
#: (wi, wo) pairs in the shading frame: normal incidence, off-specular, out of the plane, near grazing.
_PAIRS = [((0, 0), (0, 0)), ((30, 0), (40, 170)), ((60, 0), (20, 90)), ((75, 0), (70, 180))]
#: Mitsuba's BSDFs work in float32: the analytic values agree to a few ulps.
_RTOL = 2e-5


def _interaction(mi, wi):
    """A surface interaction whose shading frame is the world frame (normal +z), seen from wi."""
    si = mi.SurfaceInteraction3f()
    si.n = mi.Normal3f(0.0, 0.0, 1.0)
    si.sh_frame = mi.Frame3f(si.n)
    si.wi = mi.Vector3f(*map(float, wi))
    return si


def _eval(mi, bsdf, wi, wo, component=None):
    """BSDF times cos(theta_o) (Mitsuba's eval); ``component`` selects one lobe."""
    ctx = mi.BSDFContext()
    if component is not None:
        ctx.component = component
    return np.array(bsdf.eval(ctx, _interaction(mi, wi), mi.Vector3f(*map(float, wo))), float)


def _sample(mi, bsdf, wi, s1=0.5, s2=(0.3, 0.6)):
    """(direction, weight = BSDF cos / pdf, pdf) of one importance-sampled reflection."""
    bs, weight = bsdf.sample(mi.BSDFContext(), _interaction(mi, wi), s1, mi.Point2f(*s2))
    return np.array(bs.wo, float), np.array(weight, float), float(bs.pdf)


def _load(mi, spec):
    from roomlight.fitting.scene.description import MaterialSpec

    return mi.load_dict(MaterialSpec.parse(spec, "m").bsdf())


def _check_lambertian(mi, spec, rho):
    bsdf = _load(mi, spec)
    for (ti, pi), (to, po) in _PAIRS:
        wi, wo = direction(ti, pi), direction(to, po)
        np.testing.assert_allclose(_eval(mi, bsdf, wi, wo), np.asarray(rho) / math.pi * wo[2], rtol=_RTOL)
    for u in [(0.1, 0.2), (0.5, 0.5), (0.9, 0.7)]:
        # cosine-weighted sampling: every sample's weight is the albedo itself
        wo, weight, pdf = _sample(mi, bsdf, direction(35, 20), s2=u)
        assert wo[2] > 0 and pdf == pytest.approx(wo[2] / math.pi, rel=_RTOL)
        np.testing.assert_allclose(weight, rho, rtol=_RTOL)


def _silver(mi, bsdf):
    """(eta, k) of a conductor BSDF, after checking that they are silver's: Ag reflects 90-98 % of
    visible light at normal incidence, more towards the red (Johnson & Christy 1972)."""
    p = mi.traverse(bsdf)
    eta, k = np.array(p["eta.value"], float), np.array(p["k.value"], float)
    f0 = conductor_f0(eta, k)
    assert (f0 > 0.88).all() and (f0 < 0.99).all() and f0[0] > f0[1] > f0[2], f0
    return eta, k


def _check_diffuse(mi):
    _check_lambertian(mi, {"type": "diffuse"}, [0.5] * 3)                       # the documented default
    _check_lambertian(mi, {"type": "diffuse", "reflectance": [0.2, 0.5, 0.8]}, [0.2, 0.5, 0.8])


def _check_white(mi):
    _check_lambertian(mi, {"type": "white"}, [1.0] * 3)                         # a furnace: albedo 1


def _check_matte(mi):
    for spec, alpha in [({"type": "matte"}, 0.2), ({"type": "matte", "alpha": 0.35}, 0.35)]:
        bsdf = _load(mi, spec)
        eta, k = _silver(mi, bsdf)
        for (ti, pi), (to, po) in _PAIRS:
            wi, wo = direction(ti, pi), direction(to, po)
            want = microfacet_reflection(wi, wo, alpha, lambda c, eta=eta, k=k: fresnel_conductor(c, eta, k))
            np.testing.assert_allclose(_eval(mi, bsdf, wi, wo), want, rtol=_RTOL)
        # by hand at normal incidence: h = n, D = 1 / (pi alpha^2), no masking: F0 / (4 pi alpha^2)
        up = direction(0)
        np.testing.assert_allclose(_eval(mi, bsdf, up, up), conductor_f0(eta, k) / (4 * math.pi * alpha ** 2),
                                   rtol=_RTOL)


def _check_mirror(mi):
    bsdf = _load(mi, {"type": "mirror"})
    eta, k = _silver(mi, bsdf)
    for theta in (0.0, 60.0, 80.0):
        wi = direction(theta, 30.0)
        wo, weight, _ = _sample(mi, bsdf, wi)
        np.testing.assert_allclose(wo, reflect(wi), atol=1e-6)                  # the mirror direction, always
        np.testing.assert_allclose(weight, fresnel_conductor(math.cos(math.radians(theta)), eta, k), rtol=_RTOL)
        if theta == 0.0:
            np.testing.assert_allclose(weight, conductor_f0(eta, k), rtol=_RTOL)
        assert not _eval(mi, bsdf, wi, reflect(wi)).any()                       # a delta lobe has no density


def _check_principled(mi):
    cases = [({}, (0.5, 0.5, 0.5), 0.5, 0.0),                                  # the documented defaults
             ({"base_color": [0.8, 0.3, 0.1], "roughness": 0.3}, (0.8, 0.3, 0.1), 0.3, 0.0),
             ({"base_color": [0.9, 0.6, 0.2], "roughness": 0.4, "metallic": 1.0}, (0.9, 0.6, 0.2), 0.4, 1.0),
             ({"base_color": [0.2, 0.7, 0.4], "roughness": 0.8, "metallic": 1.0}, (0.2, 0.7, 0.4), 0.8, 1.0)]
    up = direction(0)
    for params, base, rough, metal in cases:
        bsdf = _load(mi, {"type": "principled", **params})
        for (ti, pi), (to, po) in _PAIRS:
            wi, wo = direction(ti, pi), direction(to, po)
            np.testing.assert_allclose(_eval(mi, bsdf, wi, wo), principled(base, rough, metal, wi, wo), rtol=_RTOL)
        # by hand at normal incidence (alpha = roughness^2, D = 1 / (pi alpha^2), no masking; the Schlick and
        # retro-reflection terms vanish): a metal reflects F0 = base_color, a dielectric F0 = 0.04 (eta 1.5)
        # on top of its diffuse base_color / pi
        a2 = rough ** 4
        want = (np.asarray(base) / (4 * math.pi * a2) if metal
                else np.asarray(base) / math.pi + 0.04 / (4 * math.pi * a2))
        np.testing.assert_allclose(_eval(mi, bsdf, up, up), want, rtol=_RTOL)


def _check_glossy(mi):
    bsdf = _load(mi, {"type": "glossy"})
    eta, alpha, rho = 1.49 / 1.000277, 0.08, 0.15    # polypropylene in air (Mitsuba's defaults), GGX 0.08
    p = mi.traverse(bsdf)
    assert float(p["eta"]) == pytest.approx(eta, rel=1e-6) and float(p["alpha"]) == pytest.approx(alpha, rel=1e-6)
    # the specular lobe alone (component 0): the rough dielectric interface
    for (ti, pi), (to, po) in _PAIRS + [((30, 0), (30, 180))]:
        wi, wo = direction(ti, pi), direction(to, po)
        want = microfacet_reflection(wi, wo, alpha, lambda c: fresnel_dielectric(c, eta))
        np.testing.assert_allclose(_eval(mi, bsdf, wi, wo, component=0), [want] * 3, rtol=_RTOL)
    # the diffuse lobe alone (component 1): rho / (1 - R_int) t(cos_i) t(cos_o) cos_o / (pi eta^2), with t the
    # light the rough interface lets through and R_int = 2 int R(mu) mu dmu its internal diffuse reflectance
    up = direction(0)
    base = _eval(mi, bsdf, up, up, component=1)
    assert base[0] == base[1] == base[2]                                        # a grey base
    t_up, t_60 = rough_interface(1.0, eta, alpha)[1], rough_interface(0.5, eta, alpha)[1]
    # the angular shape: Mitsuba tabulates t on 64 cosines and interpolates (0.13 % at cos 0.5)
    ratio = _eval(mi, bsdf, direction(60, 0), up, component=1) / base
    np.testing.assert_allclose(ratio, t_60 / t_up, rtol=5e-3)
    nodes, weights = np.polynomial.legendre.leggauss(32)
    mu, w = 0.5 * (nodes + 1), 0.5 * weights
    r_int = 2 * sum(wq * mq * rough_interface(mq, 1 / eta, alpha)[0] for mq, wq in zip(mu, w))
    # Mitsuba estimates R_int by the mean of R(mu) mu over 64 evenly spaced mu, 1/64 below the integral
    # (the integrand vanishes at mu = 0): 1.9 % on this lobe, hence 3 %
    np.testing.assert_allclose(base, rho / (1 - r_int) * t_up ** 2 / (math.pi * eta ** 2), rtol=0.03)


_MATERIAL_CHECKS = {"diffuse": _check_diffuse, "white": _check_white, "matte": _check_matte,
                    "mirror": _check_mirror, "principled": _check_principled, "glossy": _check_glossy}


@pytest.mark.mitsuba
@pytest.mark.parametrize("kind", MATERIAL_TYPES)
def test_every_material_gives_a_mitsuba_bsdf(mi_scalar, kind):
    """Each material kind's Mitsuba BSDF evaluates as its reflectance model, written out in
    tests/helpers_bsdf.py, with the parameters the scene gave it (and the documented defaults)."""
    assert kind in _MATERIAL_CHECKS, f"material {kind!r} has no check against its reflectance model"
    _MATERIAL_CHECKS[kind](mi_scalar)


# ------------------------------------------------------------------------------- invalid fields
def _set(path, value):
    """A mutation setting data[path...] = value (value ... deletes the key)."""
    def apply(d):
        node = d
        for k in path[:-1]:
            node = node[k]
        if value is ...:
            del node[path[-1]]
        else:
            node[path[-1]] = value
    return apply


INVALID = [
    (_set(["version"], 2), "scene.json.version: this roomlight reads version 1, got 2"),
    (_set(["objects"], ...), "scene.json.objects: missing (required)"),
    (_set(["objects"], {"a": 1}), "scene.json.objects: expected list, got {'a': 1}"),
    (_set(["objects", 0, "id"], ...), "scene.json.objects[0].id: missing (required)"),
    (_set(["objects", 0, "id"], 7), "scene.json.objects[0].id: expected str, got 7"),
    (_set(["objects", 0, "mesh"], "meshes/torus.ply"), "scene.json.objects[0]: give exactly one of 'shape'"),
    (_set(["objects", 0, "shape"], ...), "scene.json.objects[0]: give exactly one of 'shape'"),
    (_set(["objects", 0, "shape"], "teapot"), "scene.json.objects[0].shape: unknown built-in shape 'teapot'"),
    (_set(["objects", 1, "mesh"], "nothere.ply"), "scene.json.objects[1].mesh: file "),
    (_set(["objects", 1, "mesh"], "input.png"), "scene.json.objects[1].mesh: input.png: expected a .ply or .obj file"),
    (_set(["objects", 0, "translate"], [0, 1]), "scene.json.objects[0].translate: expected 3 finite numbers, got [0, 1]"),
    (_set(["objects", 0, "translate"], [0, "x", 1]), "scene.json.objects[0].translate: expected 3 finite numbers"),
    (_set(["objects", 0, "scale"], -1), "scene.json.objects[0].scale: expected a positive number, got -1"),
    (_set(["objects", 0, "scale"], "big"), "scene.json.objects[0].scale: expected a positive number, got 'big'"),
    (_set(["objects", 0, "rotate"], [0, 1, 0]), "scene.json.objects[0].rotate: expected 4 finite numbers"),
    (_set(["objects", 0, "material"], {"type": "gold"}), "scene.json.objects[0].material.type: expected one of diffuse, matte, mirror, principled, glossy, white, got 'gold'"),
    (_set(["objects", 0, "material"], {"alpha": 0.1}), "scene.json.objects[0].material.type: missing (required)"),
    (_set(["objects", 1, "material", "alpha"], 2), "scene.json.objects[1].material.alpha: expected a value in [0, 1], got 2"),
    (_set(["objects", 0, "material", "reflectance"], [1, 1]), "scene.json.objects[0].material.reflectance: expected 3 finite numbers"),
    (_set(["objects", 1, "id"], "a"), "scene.json.objects[1].id: duplicate id 'a'"),
    (_set(["views"], ...), "scene.json.views: missing (required)"),
    (_set(["views"], {}), "scene.json.views: at least one view is required"),
    (_set(["views"], ["input"]), "scene.json.views: expected dict, got ['input']"),
    (_set(["views", "input", "objects"], ["a", "zz"]), "scene.json.views.input.objects[1]: no object with id 'zz' (known: a, b, c, d)"),
    (_set(["views", "input", "objects"], ...), "scene.json.views.input.objects: missing (required)"),
    (_set(["views", "input", "camera"], ...), "scene.json.views.input.camera: missing (required)"),
    (_set(["views", "input", "camera", "width"], ...), "scene.json.views.input.camera.width: missing (required)"),
    (_set(["views", "input", "camera", "height"], 0), "scene.json.views.input.camera.height: expected a positive number, got 0"),
    (_set(["views", "input", "camera", "fov"], 200), "scene.json.views.input.camera.fov: must be below 180 degrees, got 200.0"),
    (_set(["views", "input", "camera", "fov"], -5), "scene.json.views.input.camera.fov: expected a positive number, got -5"),
    (_set(["views", "input", "camera", "target"], [0, 0, 0]), "scene.json.views.input.camera: origin and target coincide"),
    (_set(["views", "input", "camera", "up"], "y"), "scene.json.views.input.camera.up: expected 3 finite numbers, got 'y'"),
    (_set(["views", "input", "image"], "missing.exr"), "scene.json.views.input.image: file "),
    (_set(["views", "input", "mask"], 3), "scene.json.views.input.mask: expected a file path, got 3"),
    (_set(["emitter", "panorama"], ...), "scene.json.emitter.panorama: missing (required)"),
    (_set(["emitter", "panorama"], "nope.exr"), "scene.json.emitter.panorama: file "),
    (_set(["emitter", "depth"], "nope.npy"), "scene.json.emitter.depth: file "),
    (_set(["emitter"], "room.exr"), "scene.json.emitter: expected dict, got 'room.exr'"),
    (_set(["metadata"], [1]), "scene.json.metadata: expected dict, got [1]"),
]


@pytest.mark.parametrize("mutate,message", INVALID, ids=[m for _, m in INVALID])
def test_invalid_field_is_rejected_naming_it(scene_dir, mutate, message):
    root, data = scene_dir
    d = copy.deepcopy(data)
    mutate(d)
    with pytest.raises(SceneError) as exc:
        load_scene(_write(root, d))
    assert str(exc.value).startswith(message), str(exc.value)
    assert "\n" not in str(exc.value)


def test_missing_file_message_names_the_resolved_path(scene_dir):
    root, data = scene_dir
    d = copy.deepcopy(data)
    d["objects"][1]["mesh"] = "meshes/gone.ply"
    with pytest.raises(SceneError, match=r"objects\[1\]\.mesh: file .*meshes/gone\.ply does not exist"):
        load_scene(_write(root, d))


def test_non_numeric_material_parameter_is_a_scene_error(scene_dir):
    root, data = scene_dir
    d = copy.deepcopy(data)
    d["objects"][1]["material"]["alpha"] = "rough"
    with pytest.raises(SceneError, match=r"objects\[1\]\.material\.alpha"):
        load_scene(_write(root, d))


@pytest.mark.parametrize("material, key", [({"type": "diffuse", "base_color": [1, 0, 0]}, "base_color"),
                                           ({"type": "mirror", "alpha": 0.3}, "alpha"),
                                           ({"type": "white", "reflectance": [0.2, 0.2, 0.2]}, "reflectance"),
                                           ({"type": "principled", "alpha": 0.1}, "alpha")])
def test_a_parameter_the_material_type_does_not_read_is_refused(scene_dir, material, key):
    """Silently rendering a red diffuse object grey would be worse than an error."""
    root, data = scene_dir
    d = copy.deepcopy(data)
    d["objects"][1]["material"] = material
    with pytest.raises(SceneError, match=rf"objects\[1\]\.material\.{key}: a {material['type']} material does not take it"):
        load_scene(_write(root, d))


# ------------------------------------------------------------------------------- unreadable files
def test_scene_file_problems(tmp_path):
    with pytest.raises(SceneError, match="no such scene file"):
        load_scene(tmp_path / "nothing.json")
    (tmp_path / "bad.json").write_text("{ not json")
    with pytest.raises(SceneError, match=r"bad\.json: not valid JSON"):
        load_scene(tmp_path / "bad.json")
    (tmp_path / "bad.yaml").write_text("objects: [a, b\n  views: {")
    with pytest.raises(SceneError, match=r"bad\.yaml: not valid YAML"):
        load_scene(tmp_path / "bad.yaml")
    (tmp_path / "list.json").write_text("[1, 2]")
    with pytest.raises(SceneError, match=r"^list\.json: expected a mapping, got list"):
        load_scene(tmp_path / "list.json")


@pytest.mark.mitsuba
def test_corrupt_mesh_is_rejected_naming_the_file(scene_dir, mi):
    from roomlight.fitting.scene.build import object_geometry

    root, data = scene_dir
    path = _write(root, data)
    scene = load_scene(path)
    (root / "meshes" / "torus.ply").write_bytes(b"ply\nformat nonsense\n")
    with pytest.raises(SceneError, match=r"torus\.ply: Mitsuba could not read the mesh"):
        object_geometry(scene.objects["b"])
    with pytest.raises(SceneError, match=r"torus\.ply: Mitsuba could not read the mesh"):
        load_scene(path)  # rejected up front when the scene is loaded


def test_corrupt_panorama_is_rejected_naming_the_file(scene_dir):
    from roomlight.errors import RoomlightError

    root, data = scene_dir
    path = _write(root, data)
    scene = load_scene(path)
    (root / "room.exr").write_bytes(b"not an exr")
    with pytest.raises(RoomlightError, match=r"room\.exr"):
        scene.emitter.load()
    with pytest.raises(RoomlightError, match=r"room\.exr"):
        load_scene(path)  # rejected up front when the scene is loaded


def test_unreadable_or_mismatched_view_files_are_rejected_naming_the_file(scene_dir):
    from roomlight.fitting.scene.build import load_view_target

    root, data = scene_dir
    scene = load_scene(_write(root, data))
    img, mask = load_view_target(scene.views["input"], prefer="ldr")
    assert img.shape == (6, 8, 3) and mask.all()
    np.testing.assert_allclose(img.numpy(), (128 / 255) ** 2.2, rtol=1e-5)
    (root / "mask.png").write_bytes(b"garbage")
    with pytest.raises(SceneError, match=r"mask\.png: cannot read the mask"):
        load_view_target(scene.views["input"])
    save_png(root / "mask.png", np.zeros((5, 8), np.uint8))
    with pytest.raises(SceneError, match=r"mask\.png: mask is 8x5, image is 8x6"):
        load_view_target(scene.views["input"])
    save_png(root / "input.png", np.zeros((4, 4, 3), np.uint8))
    with pytest.raises(SceneError, match=r"input\.png: image is 4x4 but view 'input''s camera is 8x6"):
        load_view_target(scene.views["input"])
    (root / "input.png").write_bytes(b"garbage")
    with pytest.raises(SceneError, match=r"input\.png: cannot read the image"):
        load_view_target(scene.views["input"])


def test_unreadable_files_are_rejected_when_loading(scene_dir):
    root, data = scene_dir
    (root / "room.exr").write_bytes(b"not an exr")
    with pytest.raises(Exception, match=r"room\.exr"):
        load_scene(_write(root, data))


# ------------------------------------------------------------------------------- built-in shapes
def _weld(v: np.ndarray, f: np.ndarray, tol: float = 1e-6):
    """Merge coincident vertices and drop the faces that become degenerate."""
    keys = np.round(v / tol).astype(np.int64)
    _, index, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    f = inverse.reshape(-1)[f]
    ok = (f[:, 0] != f[:, 1]) & (f[:, 1] != f[:, 2]) & (f[:, 0] != f[:, 2])
    return v[index], f[ok]


def _components(n: int, f: np.ndarray) -> np.ndarray:
    parent = np.arange(n)

    def find(a):
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    for a, b, c in f:
        for x, y in ((a, b), (b, c)):
            rx, ry = find(x), find(y)
            if rx != ry:
                parent[rx] = ry
    return np.array([find(i) for i in range(n)])


@pytest.mark.parametrize("name", BUILTIN_SHAPES)
def test_builtin_shape_is_closed_outward_and_unit(name):
    v0, f0 = builtin_shape(name)
    assert v0.dtype == np.float32 and f0.shape[1] == 3
    r = np.linalg.norm(v0, axis=1)
    assert math.isclose(float(r.max()), 1.0, rel_tol=1e-5)
    np.testing.assert_allclose(0.5 * (v0.max(0) + v0.min(0)), 0.0, atol=1e-5)
    v, f = _weld(v0.astype(np.float64), f0.astype(np.int64))
    # Closed 2-manifold with consistent winding: every directed edge once, and its reverse once.
    directed = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    as_set = {tuple(e) for e in directed.tolist()}
    assert len(as_set) == len(directed), f"{name}: a directed edge is used twice (inconsistent winding)"
    missing = [e for e in as_set if (e[1], e[0]) not in as_set]
    assert not missing, f"{name}: {len(missing)} boundary edges (not closed)"
    # Outward: each connected part encloses a positive signed volume.
    comp = _components(len(v), f)[f[:, 0]]
    for c in np.unique(comp):
        g = f[comp == c]
        vol = np.einsum("ij,ij->i", v[g[:, 0]], np.cross(v[g[:, 1]], v[g[:, 2]])).sum() / 6.0
        assert vol > 0, f"{name}: part {c} faces inward (signed volume {vol})"


def test_unknown_builtin_shape():
    from roomlight.errors import RoomlightError

    with pytest.raises(RoomlightError, match="unknown built-in shape 'teapot'; choose one of knot"):
        builtin_shape("teapot")


def test_documented_example_loads(tmp_path):
    """The YAML example of docs/scene-format.md is a valid scene."""
    import re
    from pathlib import Path

    doc = (Path(__file__).parents[1] / "docs" / "scene-format.md").read_text()
    example = re.search(r"```yaml\n(.*?)```", doc, re.DOTALL).group(1)
    rad, depth = example_room(8)
    write_panorama(tmp_path / "room.exr", (rad.numpy(), depth.numpy()))
    (tmp_path / "meshes").mkdir()
    write_ply(tmp_path / "meshes" / "bunny.ply", *builtin_shape("blob"))
    write_exr(tmp_path / "input.exr", {c: np.zeros((128, 128), np.float32) for c in "RGB"})
    save_png(tmp_path / "input.png", np.zeros((128, 128, 3), np.uint8))
    save_png(tmp_path / "input_mask.png", np.zeros((128, 128), np.uint8))
    (tmp_path / "scene.yaml").write_text(example)
    s = load_scene(tmp_path / "scene.yaml")
    assert list(s.objects) == ["bunny", "knot", "probe"] and s.objects["probe"].material.type == "mirror"
    assert s.views["input"].objects == ["bunny", "knot"] and s.views["eval"].camera.fov == 65
    assert s.emitter.load().depth is not None
