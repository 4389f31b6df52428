"""The photo benchmark: camera, depth and masks against independent ray casts, truth probes, noise
floor, resuming, degraded depth, scoring with a true and a wrong light, runner, report and CLI."""

import json
import math
import shutil
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import torch
from click.testing import CliRunner

from roomlight.errors import RoomlightError
from roomlight.fitting.photo.camera import PhotoCamera
from roomlight.evaluation.photobench.config import PhotoBenchConfig
from roomlight.evaluation.photobench.degrade import degrade_depth, smooth_field

#: The smallest photos the staging accepts: a few seconds of rendering each.
TINY = PhotoBenchConfig(n=1, width=96, height=72, spp=16, probe_spp=128, insert_spp=256, oracle_height=16,
                        oracle_spp=16, probes=2, min_pixels=8)


# ------------------------------------------------------------------------------ independent geometry
def _rot(yaw, pitch, roll):
    """R_y(yaw) R_x(pitch) R_z(roll), written out (degrees)."""
    y, p, r = (math.radians(a) for a in (yaw, pitch, roll))
    ry = np.array([[math.cos(y), 0, math.sin(y)], [0, 1, 0], [-math.sin(y), 0, math.cos(y)]])
    rx = np.array([[1, 0, 0], [0, math.cos(p), -math.sin(p)], [0, math.sin(p), math.cos(p)]])
    rz = np.array([[math.cos(r), -math.sin(r), 0], [math.sin(r), math.cos(r), 0], [0, 0, 1]])
    return ry @ rx @ rz


def _rays(camera: PhotoCamera, x, y):
    """Unit world directions through film points, from the intrinsics written out."""
    m = camera.matrix
    q = np.stack([(x - camera.cx) / camera.fx, -(y - camera.cy) / camera.fy, -np.ones_like(x)], -1)
    d = q @ m[:3, :3].T
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


def _ray_triangles(o, d, v, f):
    """Nearest hit distance (N,) of rays (origin o (3,), unit directions d (N, 3)) with the triangles
    (Moller-Trumbore, float64, both sides); inf where a ray misses."""
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    e1, e2 = b - a, c - a
    out = np.full(len(d), np.inf)
    for s in range(0, len(d), 64):
        dd = d[s:s + 64, None, :]
        p = np.cross(dd, e2[None])
        det = np.einsum("nfk,fk->nf", p, e1)
        ok = np.abs(det) > 1e-14
        inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
        tv = o - a
        u = np.einsum("nfk,fk->nf", p, tv) * inv
        q = np.cross(tv, e1)
        vv = np.einsum("nk,fk->nf", d[s:s + 64], q) * inv
        t = np.einsum("fk,fk->f", e2, q)[None] * inv
        hit = ok & (u >= 0) & (vv >= 0) & (u + vv <= 1) & (t > 1e-9)
        out[s:s + 64] = np.where(hit, t, np.inf).min(1)
    return out


def _slab(o, d, lo, hi):
    """(t_near, t_far) of rays against an axis-aligned box; t_near > t_far where they miss."""
    with np.errstate(divide="ignore", invalid="ignore"):
        t1, t2 = (lo - o) / d, (hi - o) / d
    return np.max(np.minimum(t1, t2), -1), np.min(np.maximum(t1, t2), -1)


# ------------------------------------------------------------------------------ no Mitsuba
def test_camera_projects_what_its_rays_see_and_reports_yaw_pitch_roll():
    for yaw, pitch, roll in [(30.0, -25.0, 0.0), (-140.0, 10.0, 7.0), (95.0, -60.0, -12.0)]:
        m = np.eye(4)
        m[:3, :3], m[:3, 3] = _rot(yaw, pitch, roll), (1.0, 1.6, -2.0)
        cam = PhotoCamera(64, 48, 50.0, 52.0, 33.0, 23.5, m)
        got = cam.orientation_deg()
        assert np.allclose(got, (yaw, pitch, roll), atol=1e-9)
        x, y = np.array([0.5, 10.25, 63.5]), np.array([0.5, 30.0, 47.5])
        d = _rays(cam, x, y)
        assert np.allclose(cam.directions(x, y), d)
        xy, z = cam.project(cam.origin + 2.5 * d)
        assert np.allclose(xy, np.stack([x, y], -1)) and np.allclose(z, 2.5 * (d @ cam.forward))
    cam = PhotoCamera.look_at((0, 1.6, 0), (1.0, 0.6, -2.0), 60.0, 128, 96)
    _, pitch, roll = cam.orientation_deg()
    assert pitch == pytest.approx(math.degrees(math.atan2(-1.0, math.sqrt(5.0)))) and roll == pytest.approx(0, abs=1e-9)
    assert cam.fov_x == pytest.approx(60.0) and (cam.cx, cam.cy) == (64.0, 48.0)
    with pytest.raises(RoomlightError, match="rigid"):
        PhotoCamera(8, 8, 5, 5, 4, 4, np.diag([2.0, 2.0, 2.0, 1.0]))


def test_case_camera_json_is_the_photo_case_format():
    from roomlight.evaluation.photobench.case import camera_json

    cam = PhotoCamera.look_at((0, 1.5, 0), (0.3, 0.4, -2.0), 55.0, 80, 60)
    d = camera_json(cam)
    assert set(d) == {"format", "version", "width", "height", "intrinsics", "depth_kind", "pitch_deg", "roll_deg",
                      "units"}
    assert d["format"] == "roomlight.photo-case" and d["depth_kind"] == "z" and d["units"] == "m"
    assert d["intrinsics"] == {"fx": cam.fx, "fy": cam.fy, "cx": 40.0, "cy": 30.0}
    f = cam.forward
    assert d["pitch_deg"] == pytest.approx(math.degrees(math.asin(f[1]))) and abs(d["roll_deg"]) < 1e-9


def test_degraded_depth_is_scale_times_a_smooth_lognormal_field():
    rng = np.random.default_rng(3)
    depth = rng.uniform(0.5, 6.0, (40, 56)).astype(np.float32)
    assert np.array_equal(degrade_depth(depth), depth)
    assert np.allclose(degrade_depth(depth, scale=1.3), 1.3 * depth.astype(np.float64), rtol=1e-6)
    out = degrade_depth(depth, 0.1, 1.3, np.random.default_rng(5))
    log_ratio = np.log(out / depth.astype(np.float64)) - math.log(1.3)
    assert np.sqrt(np.mean(log_ratio ** 2)) == pytest.approx(0.1, rel=1e-4)
    field = smooth_field(40, 56, np.random.default_rng(5))
    assert np.allclose(log_ratio, 0.1 * field, atol=1e-5)
    # smooth: neighbouring pixels differ far less than the field's own spread
    assert np.abs(np.diff(field, axis=1)).mean() < 0.2
    with pytest.raises(ValueError, match="random generator"):
        degrade_depth(depth, 0.1)


def test_material_errors_by_hand():
    from roomlight.evaluation.photobench.objects import PrincipledMaterial
    from roomlight.evaluation.photobench.scoring import material_errors

    truth = {1: PrincipledMaterial((0.2, 0.4, 0.6), 0.3, 0.0), 2: PrincipledMaterial((0.5, 0.5, 0.5), 0.7, 1.0)}
    got = material_errors(truth, {"1": {"albedo": [0.3, 0.4, 0.6], "roughness": 0.5, "metallic": 0.25}})
    assert got["missing"] == [2] and got["objects"] == 2
    assert got["per_object"]["1"] == pytest.approx({"albedo_rmse": math.sqrt(0.01 / 3), "roughness_error": 0.2,
                                                    "metallic_error": 0.25})
    assert got["mean"] == got["per_object"]["1"]


def test_settings_refuse_what_cannot_work():
    for bad, msg in [({"objects": (1, 2)}, "range from 2"), ({"depth_noise": -0.1}, "depth-noise"),
                     ({"depth_scale": 0.0}, "depth-scale"), ({"width": 4}, "8x8")]:
        with pytest.raises(RoomlightError, match=msg):
            replace(PhotoBenchConfig(), **bad)
    assert "n" not in TINY.scene_settings() and "depth_noise" not in TINY.scene_settings()


def test_similarity_parts_refuse_shear_and_mirror():
    from roomlight.evaluation.photobench.scoring import similarity_parts

    m = np.eye(4)
    m[:3, :3] = 2.0 * _rot(40, 10, 0)
    m[:3, 3] = (1, 2, 3)
    s, r, t = similarity_parts(m)
    assert s == pytest.approx(2.0) and np.allclose(r, _rot(40, 10, 0)) and np.allclose(t, (1, 2, 3))
    for bad in (np.diag([1.0, 2.0, 1.0, 1.0]), np.diag([-1.0, 1.0, 1.0, 1.0])):
        with pytest.raises(RoomlightError):
            similarity_parts(bad)


# ------------------------------------------------------------------------------ Mitsuba: box room
@pytest.mark.mitsuba
def test_depth_and_coverage_match_analytic_ray_casts_in_a_box_room(mi):
    from roomlight.evaluation.photobench.objects import InsertedObject, PrincipledMaterial
    from roomlight.evaluation.photobench.roomscene import RoomScenes
    from roomlight.evaluation.photobench.tracing import trace_coverage, trace_depth
    from roomlight.datagen.synth.rooms import box_room

    size = (4.0, 2.7, 5.0)
    scenes = RoomScenes(box_room(size), max_depth=3)
    box = InsertedObject("obj1", 1, "box", (0.6, 0.4, 0.5), 0.0, (2.0, 0.2, 1.5), PrincipledMaterial((0.5,) * 3, 0.5, 0))
    mesh = box.mitsuba_mesh()
    scene = scenes.scene({"obj1": mesh})
    cam = PhotoCamera.look_at((3.2, 1.6, 4.2), (2.0, 0.3, 1.5), 70.0, 64, 48)
    depth = trace_depth(scene, cam)
    x, y = cam.pixel_centres()
    d = _rays(cam, x, y)
    o = cam.origin
    lo, hi = np.array([1.7, 0.0, 1.25]), np.array([2.3, 0.4, 1.75])
    tn, tf = _slab(o, d, lo, hi)
    t_box = np.where((tn <= tf) & (tn > 0), tn, np.inf)
    _, t_room = _slab(o, d, np.zeros(3), np.array(size))  # from inside the room: the far side of its box
    t = np.minimum(t_box, t_room)
    want = (t * (d @ cam.forward)).reshape(48, 64)
    assert np.abs(depth - want).max() < 1e-4 * want.max()
    # coverage: the same 4 x 4 sub-pixel rays, cast analytically
    cov = trace_coverage(scene, cam, [mesh], 4)[0]
    s = 4
    jj, ii = np.meshgrid((np.arange(64 * s) + 0.5) / s, (np.arange(48 * s) + 0.5) / s)
    ds = _rays(cam, jj.ravel(), ii.ravel())
    tn, tf = _slab(o, ds, lo, hi)
    hit = ((tn <= tf) & (tn > 0)).reshape(48, s, 64, s).mean(axis=(1, 3))
    assert hit.sum() > 50
    # sub-rays grazing an edge may go either way in float32: allow a handful
    assert np.abs(cov - hit).sum() <= 4 / 16


# ------------------------------------------------------------------------------ a built photo
@pytest.fixture(scope="module")
def built(tmp_path_factory):
    from roomlight.evaluation.photobench.builder import make_photo_benchmark

    out = tmp_path_factory.mktemp("photos") / "bench"
    manifest = make_photo_benchmark(out, TINY, progress=False)
    assert manifest["built"] == ["photo-00000"] and not manifest["failed"]
    return out


def _case(built):
    return built / "photo-00000"


@pytest.mark.mitsuba
def test_case_folder_manifest_and_exposure(built):
    from roomlight.core.color import log_average_np
    from roomlight.evaluation.photobench import case as fmt

    manifest = json.loads((built / "manifest.json").read_text())
    assert manifest["kind"] == "photos" and [p["id"] for p in manifest["photos"]] == ["photo-00000"]
    d = _case(built)
    for name in (fmt.IMAGE, fmt.DEPTH, fmt.MASK, fmt.CAMERA, fmt.RECORD, fmt.MATERIALS, fmt.PROBES, fmt.TRUE_DEPTH,
                 fmt.TRUE_CAMERA, fmt.PROBE_MASK, fmt.ORACLE, fmt.PREVIEW,
                 *[fmt.probe_image_name(m, e) for m in ("diffuse", "matte", "mirror") for e in ("exr", "png")]):
        assert (d / name).is_file(), name
    assert not list(built.glob(".*partial*"))
    image = fmt.read_rgb_exr(d / fmt.IMAGE)
    assert image.shape == (72, 96, 3) and np.isfinite(image).all() and image.min() >= 0
    # the camera meters the whole frame: k = key / log-average luminance of the unexposed render
    k = json.loads((d / fmt.RECORD).read_text())["exposure"]
    assert k * log_average_np(image.astype(np.float64) / k) == pytest.approx(TINY.key, rel=1e-4)
    labels = fmt.read_labels(d / fmt.MASK)
    mats = json.loads((d / fmt.MATERIALS).read_text())["objects"]
    assert set(np.unique(labels)) == {0, *map(int, mats)} and 2 <= len(mats) <= 3
    record = json.loads((d / fmt.RECORD).read_text())
    for label, n in record["pixels"]["objects"].items():
        assert n == int((labels == int(label)).sum()) >= TINY.min_pixels
    for m in mats.values():
        assert m["bsdf"]["type"] == "principled" and 0 <= m["material"]["roughness"] <= 1
        assert m["material"]["metallic"] in (0.0, 1.0)


@pytest.mark.mitsuba
def test_photo_depth_and_masks_agree_with_the_objects_meshes(built):
    """Each object's mesh, ray-cast in numpy: where it is the first hit its distance is the
    photo's depth, it is never in front of that depth, and every pixel labelled k sees object k."""
    from roomlight.evaluation.photobench import case as fmt
    from roomlight.evaluation.photobench.scoring import load_truth

    d = _case(built)
    truth = load_truth(d)
    cam = truth.camera
    depth = fmt.read_depth_exr(d / fmt.TRUE_DEPTH).astype(np.float64)
    assert np.array_equal(depth, fmt.read_depth_exr(d / fmt.DEPTH))  # no degradation asked
    labels = fmt.read_labels(d / fmt.MASK)
    x, y = cam.pixel_centres()
    rays = _rays(cam, x, y)
    cos = rays @ cam.forward
    for obj in truth.objects:
        v, f = obj.geometry()
        xy, _ = cam.project(v)
        x0, y0 = np.floor(xy.min(0)).astype(int) - 1
        x1, y1 = np.ceil(xy.max(0)).astype(int) + 1
        box = np.zeros((72, 96), bool)
        box[max(y0, 0):y1 + 1, max(x0, 0):x1 + 1] = True
        assert not (labels == obj.label)[~box].any()  # labels only inside the projected object
        idx = np.flatnonzero(box.ravel())
        t = _ray_triangles(cam.origin, rays[idx], v, f)
        z = t * cos[idx]
        recorded = depth.ravel()[idx]
        tol = 2e-4 * recorded + 1e-5
        assert (z >= recorded - tol).all()  # never in front of what the photo shows
        first = np.abs(z - recorded) <= tol
        lab = labels.ravel()[idx]
        mine = lab == obj.label
        assert mine.sum() >= TINY.min_pixels and first[mine].all()  # label k: object k is the first hit
        assert set(np.unique(lab[first])) <= {0, obj.label}  # nobody else's label where k is the first hit


@pytest.mark.mitsuba
def test_truth_probes_sit_on_surfaces_fill_their_masks_and_reproduce(built):
    from roomlight.evaluation.harness.metrics import psnr_ldr
    from roomlight.evaluation.photobench import case as fmt
    from roomlight.evaluation.photobench.builder import photo_seeds, render_probe_truth
    from roomlight.evaluation.photobench.roomscene import RoomScenes
    from roomlight.evaluation.photobench.scoring import load_truth
    from roomlight.evaluation.photobench.staging import RayCaster
    from roomlight.datagen.synth.rooms import generate_room

    d = _case(built)
    truth = load_truth(d)
    record = json.loads((d / fmt.RECORD).read_text())
    cam = truth.camera
    assert [p.label for p in truth.probes] == [1, 2]
    for p in truth.probes:
        inside = cam.sphere_pixels(p.center, p.radius)
        mine = truth.probe_mask == p.label
        assert mine.sum() >= TINY.min_pixels and not (mine & ~inside).any()
        c_cam = np.linalg.inv(cam.matrix) @ np.append(p.center, 1.0)
        listed = next(q for q in record["probes"] if q["label"] == p.label)
        assert np.allclose(listed["center_camera"], c_cam[:3])
    for m, img in truth.probe_images.items():
        assert np.isfinite(img).all() and img[truth.window_mask > 0].mean() > 0, m

    # the room again, from its seed: probes rest 2 mm above a surface, and the truth re-renders bit for bit
    scenes = RoomScenes(generate_room(record["room_seed"]), TINY.max_depth)
    below = np.array([np.asarray(p.center) - [0, p.radius + 1e-3, 0] for p in truth.probes])
    t, n, _ = RayCaster(scenes.base).cast(below, np.tile([0.0, -1.0, 0.0], (len(below), 1)))
    assert np.allclose(t, 1e-3, atol=2e-4) and (n[:, 1] > 0.95).all()
    meshes = {o.id: o.mitsuba_mesh() for o in truth.objects}
    seeds = photo_seeds(TINY, 0)
    mask = truth.window_mask > 0
    assert mask.sum() == (truth.probe_mask > 0).sum()  # the window holds every probe pixel
    signal = psnr_ldr(truth.probe_images["diffuse"], truth.probe_images["mirror"], mask)
    for m in ("diffuse", "mirror"):
        scene = scenes.scene({**meshes, **{p.id: p.mitsuba_shape(m) for p in truth.probes}})
        again, _ = render_probe_truth(scene, cam, TINY.probe_spp, seeds[f"probes_{m}"], truth.window, truth.exposure)
        assert np.array_equal(again, truth.probe_images[m])
        # noise floor: the same render with other seeds agrees far better than two materials do
        other, _ = render_probe_truth(scene, cam, TINY.probe_spp, seeds[f"probes_{m}"] + 1000, truth.window,
                                      truth.exposure)
        noise = psnr_ldr(other, truth.probe_images[m], mask)
        assert noise > signal + 6, (m, noise, signal)
        for p in truth.probes:  # and each probe's mean radiance within 10 %
            a, b = other[truth.window_mask == p.label].mean(), truth.probe_images[m][truth.window_mask == p.label].mean()
            assert abs(a - b) < 0.1 * b, (m, p.label, a, b)
        floor = json.loads((d / fmt.PROBES).read_text())["noise_floor"][m]
        assert floor["pixels"] == mask.sum() and floor["psnr_ldr"] > signal


@pytest.mark.mitsuba
def test_rerun_skips_and_degraded_depth_changes_only_the_methods_depth(built, tmp_path):
    import hashlib

    from roomlight.evaluation.photobench import case as fmt
    from roomlight.evaluation.photobench.builder import make_photo_benchmark
    from roomlight.evaluation.photobench.scoring import load_truth

    out = tmp_path / "bench"
    shutil.copytree(built, out)

    def digests():
        return {str(p.relative_to(out)): hashlib.sha256(p.read_bytes()).hexdigest() for p in out.rglob("*")
                if p.is_file()}

    before = digests()
    again = make_photo_benchmark(out, TINY, progress=False)
    assert again["skipped"] == ["photo-00000"] and again["built"] == [] and again["updated"] == []
    assert digests() == before
    noisy = TINY.override(depth_noise=0.1, depth_scale=1.3)
    upd = make_photo_benchmark(out, noisy, progress=False)
    assert upd["updated"] == ["photo-00000"] and upd["built"] == []
    after = digests()
    changed = {k for k in before if before[k] != after[k]}
    assert changed == {"photo-00000/depth.exr", "photo-00000/truth/photo.json", "manifest.json"}
    d = out / "photo-00000"
    given = fmt.read_depth_exr(d / fmt.DEPTH).astype(np.float64)
    exact = fmt.read_depth_exr(d / fmt.TRUE_DEPTH).astype(np.float64)
    log_ratio = np.log(given / exact) - math.log(1.3)
    assert np.sqrt(np.mean(log_ratio ** 2)) == pytest.approx(0.1, rel=1e-3)
    assert json.loads((d / fmt.RECORD).read_text())["depth"] == {"depth_noise": 0.1, "depth_scale": 1.3}
    # the scoring places probes through that depth: the factor at each probe's centre pixel
    truth = load_truth(d)
    for p in truth.probes:
        (px, py), _ = truth.camera.project(np.asarray(p.center)[None])[0][0], None
        j, i = int(px), int(py)
        near = (given / exact)[max(i - 1, 0):i + 2, max(j - 1, 0):j + 2]
        assert near.min() - 1e-6 <= truth.depth_factors[p.id] <= near.max() + 1e-6


@pytest.mark.mitsuba
def test_a_clean_insertion_truth_is_added_in_place_unbiased_and_less_noisy(built, tmp_path):
    """Another --insert-spp renders truth/insert_clean.exr again and changes nothing else; staged again from
    its seeds it is the render a fresh build makes; it agrees with the photo-seeded truth on average, and
    its noise is as much smaller as its samples are more."""
    import hashlib

    from roomlight.evaluation.photobench import case as fmt
    from roomlight.evaluation.photobench import insertion as ins
    from roomlight.evaluation.photobench.builder import make_photo_benchmark

    out = tmp_path / "bench"
    shutil.copytree(built, out)
    truth_dir = out / "photo-00000" / fmt.TRUTH
    assert ins.insert_truth_stamp(truth_dir) == {"image": ins.INSERT_CLEAN, "spp": TINY.insert_spp}

    def digests():
        return {str(p.relative_to(out)): hashlib.sha256(p.read_bytes()).hexdigest() for p in out.rglob("*")
                if p.is_file()}

    # none: the photo as built before the clean truth existed (scored against the photo's own samples)
    none = make_photo_benchmark(out, TINY.override(insert_spp=0), progress=False)
    assert none["insert_updated"] == ["photo-00000"] and none["built"] == [] and none["updated"] == []
    assert not (truth_dir / ins.INSERT_CLEAN).exists()
    assert ins.insert_truth_stamp(truth_dir) == {"image": ins.INSERT_IMAGE, "spp": None}
    before = digests()
    more = make_photo_benchmark(out, TINY.override(insert_spp=512), progress=False)
    assert more["insert_updated"] == ["photo-00000"] and more["built"] == [] and more["skipped"] == []
    after = digests()
    changed = {k for k in after if before.get(k) != after[k]}
    assert changed == {"photo-00000/truth/insert_clean.exr", "photo-00000/truth/insert.json",
                       "photo-00000/truth/photo.json", "manifest.json"}
    assert make_photo_benchmark(out, TINY.override(insert_spp=512), progress=False)["skipped"] == ["photo-00000"]

    # the same render as a photo built from scratch with that setting, bit for bit
    fresh = tmp_path / "fresh"
    make_photo_benchmark(fresh, TINY.override(insert_spp=512), progress=False)
    clean = fmt.read_rgb_exr(truth_dir / ins.INSERT_CLEAN).astype(np.float64)
    assert np.array_equal(clean, fmt.read_rgb_exr(fresh / "photo-00000" / fmt.TRUTH / ins.INSERT_CLEAN))
    assert json.loads((truth_dir / ins.INSERT_JSON).read_text())["clean"]["spp"] == 512

    # independent seeds: the photo-seeded truth (16 spp) minus the clean one averages zero over the frame ...
    noisy = fmt.read_rgb_exr(truth_dir / ins.INSERT_IMAGE).astype(np.float64)
    diff = (noisy - clean).mean(-1).ravel()
    assert abs(diff.mean()) < 4.0 * diff.std() / math.sqrt(diff.size)
    # ... and against a third render of the scene (128 spp, a seed of the test's own) the squared differences
    # scale as 1/spp: E|noisy - clean|^2 / E|third - clean|^2 = (1/16 + 1/512) / (1/128 + 1/512) = 6.6
    from roomlight.datagen.synth.rooms import generate_room
    from roomlight.evaluation.photobench.roomscene import RoomScenes
    from roomlight.evaluation.photobench.scoring import load_truth

    record = json.loads((out / "photo-00000" / fmt.RECORD).read_text())
    truth = load_truth(out / "photo-00000")
    _, labels, objects = ins.read_insert_truth(truth_dir)
    third, again = ins.render_insert_truth(RoomScenes(generate_room(record["room_seed"]), TINY.max_depth),
                                           {o.id: o.mitsuba_mesh() for o in truth.objects}, objects, truth.camera,
                                           128, 12345, TINY.supersample, record["exposure"])
    assert np.array_equal(again, labels)
    ratio = np.mean((noisy - clean) ** 2) / np.mean((third.astype(np.float64) - clean) ** 2)
    assert 3.3 < ratio < 13.2    # within a factor 2 of 6.6 (a 1/spp law would give 1 at equal samples)


# ------------------------------------------------------------------------------ scoring
def _rolled(light, k):
    from roomlight.core.light import Light

    return Light(np.roll(light.radiance, k, axis=1), None if light.depth is None else
                 np.roll(light.depth, k, axis=1), light.kind, light.frame)


@pytest.mark.mitsuba
def test_scoring_gives_near_zero_error_for_the_true_light_and_large_for_wrong_ones(built):
    from roomlight.core.geometry.equirect import uv_to_direction
    from roomlight.evaluation.photobench.objects import PROBE_MATERIALS
    from roomlight.core.light import Light
    from roomlight.evaluation.photobench.scoring import load_truth, oracle_light, render_probes, score_light

    truth = load_truth(_case(built))
    light = oracle_light(_case(built), "mesh", truth)
    h, w = light.radiance.shape[:2]
    grey = Light(np.full_like(light.radiance, light.radiance.mean()), None, "envmap", light.frame)

    def rmse(scores):
        return {m: scores[m]["rmse_hdr"] for m in PROBE_MATERIALS}

    # A ground truth that *is* this light (the probes rendered under it with one seed): scored with
    # another seed, only Monte Carlo noise is left; a rotated or a grey light is far off.
    own = replace(truth, probe_images={m: render_probes(truth, light, m, 32, seed=11) for m in PROBE_MATERIALS})
    exact = score_light(own, light, 32, seed=99)
    for name, bad in (("half a turn", _rolled(light, w // 2)), ("grey", grey)):
        off = score_light(own, bad, 32, seed=99)
        for m in PROBE_MATERIALS:
            assert exact[m]["rmse_hdr"] < 0.25 * off[m]["rmse_hdr"], (name, m, exact[m], off[m])
            assert exact[m]["psnr_ldr"] > off[m]["psnr_ldr"] + 6, (name, m)
    for m in PROBE_MATERIALS:
        assert exact[m]["psnr_ldr"] > 28 and exact[m]["angular_error"] < 3, (m, exact[m])
        assert set(exact[m]["per_probe"]) == {"1", "2"}

    # The same light in units 2.5 times smaller (its frame scaled, its depth too): the same scores,
    # up to float rounding. (A light sits at its frame's origin: moving the frame would move the light.)
    frame = np.diag([2.5, 2.5, 2.5, 1.0])
    moved = Light(light.radiance, light.depth * 2.5, "mesh", frame @ light.frame)
    again = score_light(own, moved, 32, seed=99)
    for m in PROBE_MATERIALS:
        assert again[m]["psnr_ldr"] == pytest.approx(exact[m]["psnr_ldr"], abs=0.05)
    # ... and turned a quarter about the vertical: the panorama rolled by W/4, the frame rotated to
    # match (solved from the panorama's own pixel directions): the same light, other noise
    u = (np.arange(w) + 0.5) / w
    v = np.full(w, 0.3)
    import torch

    a = uv_to_direction(torch.from_numpy(u), torch.from_numpy(v)).numpy()
    b = uv_to_direction(torch.from_numpy((u + 0.25) % 1.0), torch.from_numpy(v)).numpy()
    a = np.concatenate([a, [[0.0, 1.0, 0.0]]])
    b = np.concatenate([b, [[0.0, 1.0, 0.0]]])
    q = np.linalg.lstsq(a, b, rcond=None)[0].T
    turn = np.eye(4)
    turn[:3, :3] = q
    turned = _rolled(light, w // 4)
    turned = turned.with_frame(turn @ light.frame)
    rot = score_light(own, turned, 32, seed=99)
    unturned = score_light(own, _rolled(light, w // 4), 32, seed=99)
    for m in PROBE_MATERIALS:
        assert rot[m]["rmse_hdr"] < 0.25 * unturned[m]["rmse_hdr"] and rot[m]["psnr_ldr"] > 25, (m, rot[m])

    # Against the real ground truth (full light transport in the room): the oracle beats wrong lights.
    real = score_light(truth, light, 32, seed=99)
    for bad in (_rolled(light, w // 2), grey):
        off = score_light(truth, bad, 32, seed=99)
        for m in PROBE_MATERIALS:
            assert real[m]["rmse_hdr"] < 0.7 * off[m]["rmse_hdr"], (m, real[m], off[m])


# ------------------------------------------------------------------------------ runner, report, CLI
def _stand_in_fit(calls):
    """A fit for the runner: the prior gets the oracle light and materials 0.1 rougher than true; the
    env-map baseline a grey env map and albedos 0.05 brighter; anything else fails."""
    from roomlight.evaluation.photobench.scoring import load_truth, oracle_light

    def fit(case_dir, method, preset, out_dir, model=None, progress=False, overrides=None):
        calls.append((Path(case_dir).name, method, preset))
        truth = load_truth(case_dir)
        light = oracle_light(case_dir, "mesh", truth)
        mats = {o.label: {"albedo": list(o.material.albedo), "roughness": o.material.roughness,
                          "metallic": o.material.metallic} for o in truth.objects}
        Path(out_dir).mkdir(parents=True, exist_ok=True)
        if method == "prior":
            for m in mats.values():
                m["roughness"] = min(1.0, m["roughness"] + 0.1)
            return {"radiance": light.radiance, "depth": light.depth, "emitter_kind": "mesh",
                    "light_from_camera": light.frame, "materials": mats, "seconds": 1.5}
        if method == "direct-envmap":
            for m in mats.values():
                m["albedo"] = [a + 0.05 for a in m["albedo"]]
            return {"radiance": np.full_like(light.radiance, light.radiance.mean()), "depth": None,
                    "emitter_kind": "envmap", "light_from_camera": light.frame, "materials": mats,
                    "seconds": 0.5}
        raise RuntimeError(f"no stand-in for {method}")

    return fit


@pytest.mark.mitsuba
def test_runner_resumes_shards_records_failures_and_the_report_pairs_methods(built, tmp_path):
    from roomlight.evaluation.photobench.report import write_photo_report
    from roomlight.evaluation.photobench.runner import list_photo_cases, run_photo_benchmark

    res = tmp_path / "res"
    calls = []
    fit = _stand_in_fit(calls)
    methods = ("direct-envmap", "prior", "prior-envmap", "oracle")
    summary = run_photo_benchmark(built, res, methods, preset="fast", eval_spp=8, fit=fit, progress=False)
    assert sorted(summary.done) == ["photo-00000/direct-envmap", "photo-00000/oracle", "photo-00000/prior"]
    assert list(summary.failed) == ["photo-00000/prior-envmap"] and "no stand-in" in summary.failed["photo-00000/prior-envmap"]
    assert (res / "cases/photo-00000/prior-envmap/error.json").is_file()
    assert ("photo-00000", "prior", "fast") in calls and not any(c[1] == "oracle" for c in calls)
    prior = json.loads((res / "cases/photo-00000/prior/result.json").read_text())
    assert prior["materials"]["mean"]["roughness_error"] == pytest.approx(
        np.mean([min(1.0, o["material"]["roughness"] + 0.1) - o["material"]["roughness"]
                 for o in json.loads((_case(built) / "truth/materials.json").read_text())["objects"].values()]))
    assert prior["materials"]["mean"]["albedo_rmse"] == 0.0 and prior["materials"]["mean"]["metallic_error"] == 0.0
    base = json.loads((res / "cases/photo-00000/direct-envmap/result.json").read_text())
    assert base["materials"]["mean"]["albedo_rmse"] == pytest.approx(0.05)
    oracle = json.loads((res / "cases/photo-00000/oracle/result.json").read_text())
    assert oracle["materials"] is None and oracle["emitter_kind"] == "mesh"
    # the inserted objects composited under each light, scored in their regions
    for r in (prior, base, oracle):
        assert [e["label"] for e in r["insertion"]] == [101, 102] and (res / "cases/photo-00000" / r["method"] / "insert.exr").is_file()
    region = {r["method"]: np.mean([e["psnr_ldr"] for e in r["insertion"]]) for r in (prior, base, oracle)}
    assert region["prior"] == pytest.approx(region["oracle"], abs=1.0)  # the oracle's light, other materials
    for m in ("diffuse", "matte", "mirror"):
        # the stand-in prior returned the oracle's light: the same scores (the same seeds)
        assert prior["probes"][m]["psnr_ldr"] == pytest.approx(oracle["probes"][m]["psnr_ldr"], abs=1e-6)
        assert prior["probes"][m]["rmse_hdr"] < base["probes"][m]["rmse_hdr"]
        assert (res / f"cases/photo-00000/prior/probes_{m}.exr").is_file()

    # a rerun skips the finished cases and retries the failed one
    calls.clear()
    again = run_photo_benchmark(built, res, methods, preset="fast", eval_spp=8, fit=fit, progress=False)
    assert len(again.skipped) == 3 and list(again.failed) == ["photo-00000/prior-envmap"]
    assert calls == [("photo-00000", "prior-envmap", "fast")]
    with pytest.raises(RoomlightError, match="other settings"):
        run_photo_benchmark(built, res, methods, preset="fast", eval_spp=16, fit=fit, progress=False)
    with pytest.raises(RoomlightError, match="unknown method"):
        run_photo_benchmark(built, tmp_path / "r2", ("prior", "magic"), fit=fit, progress=False)
    shards = [list_photo_cases(built, methods, (i, 3)) for i in range(3)]
    assert sorted(c.method for s in shards for c in s) == sorted(methods)

    paths = write_photo_report(res, progress=False)
    md = paths["markdown"].read_text()
    for m in ("direct-envmap", "prior", "oracle"):
        assert f"| {m} |" in md
    assert "prior-envmap" in md and "Failed cases" in md  # the failed case is listed
    summary = json.loads(paths["json"].read_text())
    assert set(summary["paired"]["probes"]) == {"direct-envmap"}  # oracles are not baselines
    stats = summary["paired"]["probes"]["direct-envmap"]["diffuse"]["rmse_hdr"]
    assert stats["n"] == 1 and stats["wins"] == 1 and stats["better"] == "lower"
    assert summary["materials"]["direct-envmap"]["albedo_rmse"]["mean"] == pytest.approx(0.05)
    assert summary["paired"]["materials"]["direct-envmap"]["objects"]["albedo_rmse"]["mean"] == pytest.approx(-0.05)
    assert paths["figure:photo-00000"].is_file() and paths["html"].read_text().count("<figure") == 1
    assert "## Inserted objects" in md and summary["insertion"]["methods"]["prior"]["psnr_ldr"]["n"] == 2
    # the paired tables against another reference: the same differences with the sign turned
    other = write_photo_report(res, tmp_path / "vs-envmap", figures=False, progress=False, reference="direct-envmap")
    flipped = json.loads(other["json"].read_text())
    assert flipped["paired_reference"] == "direct-envmap" and set(flipped["paired"]["probes"]) == {"prior"}
    back = flipped["paired"]["probes"]["prior"]["diffuse"]["rmse_hdr"]
    assert back["mean"] == pytest.approx(-stats["mean"]) and back["wins"] == 0
    assert flipped["paired"]["materials"]["prior"]["objects"]["albedo_rmse"]["mean"] == pytest.approx(0.05)
    ins = summary["insertion"]["paired"]["direct-envmap"]["objects"]["psnr_ldr"]["mean"]
    # per photo: the photo's two objects are one draw, their mean difference the same as over the objects
    per_object = summary["insertion"]["paired"]["direct-envmap"]["objects"]["psnr_ldr"]
    by_photo = summary["insertion"]["paired_by_photo"]["direct-envmap"]["objects"]["psnr_ldr"]
    assert (per_object["n"], by_photo["n"]) == (2, 1) and by_photo["mean"] == pytest.approx(ins)
    assert "Paired per photo" in md
    assert flipped["insertion"]["paired"]["prior"]["objects"]["psnr_ldr"]["mean"] == pytest.approx(-ins)
    assert "## Paired differences on the probes: direct-envmap against each other method" in other["markdown"].read_text()
    with pytest.raises(RoomlightError, match="'veni-d' to pair the others with; the results have direct-envmap, oracle, prior"):
        write_photo_report(res, tmp_path / "vs-none", figures=False, progress=False, reference="veni-d")


def run_cli(*args):
    from roomlight.cli.main import cli

    return CliRunner().invoke(cli, [str(a) for a in args])


@pytest.mark.mitsuba
def test_cli_make_run_report_and_one_line_errors(built, tmp_path):
    out = tmp_path / "bench"
    shutil.copytree(built, out)
    make = ("bench", "make-photos", "--out", out, "--n", 1, "--res", "72x96", "--spp", 16, "--probes", 2,
            "--probe-spp", 128, "--set", "oracle_height=16", "--set", "oracle_spp=16", "--set", "min_pixels=8", "--quiet")
    r = run_cli(*make, "--insert-spp", 256)
    assert r.exit_code == 0 and "1 already built" in r.output, r.output
    res = tmp_path / "res"
    r = run_cli("bench", "run-photos", out, "--out", res, "--methods", "oracle-envmap", "--eval-spp", 4, "--quiet")
    assert r.exit_code == 0 and "1 done" in r.output, r.output
    r = run_cli("bench", "report-photos", res, "--no-figures", "--quiet")
    assert r.exit_code == 0 and "| oracle-envmap | Env map |" in r.output, r.output
    assert "Truth: the scene path-traced again at 256 samples per pixel" in (res / "report/report.md").read_text()

    # a new clean insertion truth: the finished case is scored again from its saved composite, not refitted
    record_file = res / "cases/photo-00000/oracle-envmap/result.json"
    first = json.loads(record_file.read_text())
    r = run_cli(*make, "--insert-spp", 512)
    assert r.exit_code == 0 and "1 with a new clean insertion truth" in r.output, r.output
    r = run_cli("bench", "run-photos", out, "--out", res, "--methods", "oracle-envmap", "--eval-spp", 4, "--quiet")
    assert r.exit_code == 0 and "1 scored again against a new insertion truth" in r.output, r.output
    again = json.loads(record_file.read_text())
    assert again["insertion_truth"] == {"image": "insert_clean.exr", "spp": 512}
    assert again["insertion_superseded"] == {"insertion_truth": first["insertion_truth"],
                                             "insertion": first["insertion"]}
    assert again["probes"] == first["probes"] and again["wall_seconds"] == first["wall_seconds"]
    # the object's PSNR written out: gamma 2.2 after clipping to [0, 1], over its whole pixels
    from PIL import Image

    from roomlight.evaluation.photobench import case as fmt

    composite = fmt.read_rgb_exr(record_file.parent / "insert.exr").astype(np.float64)
    clean = fmt.read_rgb_exr(out / "photo-00000/truth/insert_clean.exr").astype(np.float64)
    labels = np.asarray(Image.open(out / "photo-00000/truth/insert_mask.png"))
    for e in again["insertion"]:
        m = labels == e["label"]
        mse = np.mean((np.clip(composite[m], 0, 1) ** (1 / 2.2) - np.clip(clean[m], 0, 1) ** (1 / 2.2)) ** 2)
        assert e["object_psnr_ldr"] == pytest.approx(10 * math.log10(1 / mse), abs=1e-4)
    r = run_cli("bench", "run-photos", out, "--out", res, "--methods", "oracle-envmap", "--eval-spp", 4, "--quiet")
    assert "scored again" not in r.output and json.loads(record_file.read_text()) == again
    # a case whose composite is gone cannot be scored again: said, not silently kept
    (record_file.parent / "insert.exr").unlink()
    r = run_cli(*make, "--insert-spp", 256)
    r = run_cli("bench", "run-photos", out, "--out", res, "--methods", "oracle-envmap", "--eval-spp", 4, "--quiet")
    assert r.exit_code == 1 and "its composite (insert.exr) is gone" in r.output, r.output

    for args, message in [
        (("make-photos", "--out", tmp_path / "x", "--depth-noise", "-1"), "--depth-noise must be in [0, 1)"),
        (("make-photos", "--out", tmp_path / "x", "--insert-spp", "-1"), "--insert-spp must be at least 0"),
        (("make-photos", "--out", tmp_path / "x", "--set", "objects=[1, 2]"), "range from 2"),
        (("make-photos", "--out", tmp_path / "x", "--set", "colour=red"), "unknown field"),
        (("run-photos", tmp_path, "--out", tmp_path / "y", "--methods", "oracle"), "no manifest.json"),
        (("run-photos", out, "--out", tmp_path / "y", "--methods", "magic"), "unknown method"),
        (("report-photos", tmp_path / "nothing"), "no results"),
        (("run-photos", out, "--out", tmp_path / "y", "--methods", "oracle", "--view-encoder", tmp_path),
         "--view-encoder is read by the prior's methods only"),
    ]:
        r = run_cli("bench", *args)
        assert r.exit_code == 2, (args, r.output)
        assert message in r.output and "Traceback" not in r.output, (args, r.output)
        assert len([ln for ln in r.output.splitlines() if ln.strip()]) <= 3, r.output
    assert not (tmp_path / "y").exists()  # refused before anything is written
    # results made with the prior's own view encoder are not resumed with another one
    from roomlight.errors import RoomlightError
    from roomlight.evaluation.photobench.runner import run_photo_benchmark

    with pytest.raises(RoomlightError, match="view_encoder"):
        run_photo_benchmark(out, res, ["oracle-envmap"], eval_spp=4, progress=False, view_encoder_name="/elsewhere")


@pytest.mark.mitsuba
def test_photo_fit_reads_the_case_as_written(built):
    """The photo fit's loader reads the case folder as the benchmark meant it."""
    from roomlight.fitting.photo.case import load_photo

    from roomlight.evaluation.photobench import case as fmt
    from roomlight.evaluation.photobench.scoring import load_truth

    d = _case(built)
    case = load_photo(str(d))
    truth = load_truth(d)
    assert case.depth_kind == "z" and np.array_equal(case.depth, fmt.read_depth_exr(d / fmt.DEPTH))
    assert np.array_equal(case.objects.labels, fmt.read_labels(d / fmt.MASK))
    assert case.objects.ids == sorted(o.label for o in truth.objects)
    k = case.intrinsics
    assert (k.fx, k.fy, k.cx, k.cy) == (truth.camera.fx, truth.camera.fy, truth.camera.cx, truth.camera.cy)
    _, pitch, roll = truth.camera.orientation_deg()
    assert case.pitch_deg == pytest.approx(pitch) and case.roll_deg == pytest.approx(roll)
    assert np.array_equal(case.image, fmt.read_rgb_exr(d / fmt.IMAGE))


@pytest.mark.mitsuba
@pytest.mark.slow
def test_builds_are_deterministic_and_a_degraded_variant_differs_only_in_depth(built, tmp_path):
    import hashlib

    from roomlight.evaluation.photobench.builder import make_photo_benchmark

    out = tmp_path / "noisy"
    make_photo_benchmark(out, TINY.override(depth_noise=0.05, depth_scale=0.8), progress=False)
    a, b = _case(built), out / "photo-00000"
    files = sorted(p.relative_to(a) for p in a.rglob("*") if p.is_file())
    assert files == sorted(p.relative_to(b) for p in b.rglob("*") if p.is_file())
    differ = [str(f) for f in files if hashlib.sha256((a / f).read_bytes()).digest()
              != hashlib.sha256((b / f).read_bytes()).digest()]
    assert differ == ["depth.exr", "truth/photo.json"]
    ra, rb = (json.loads((x / "truth/photo.json").read_text()) for x in (a, b))
    for k in ("room_seed", "camera", "objects", "probes", "exposure", "seeds", "noise_floor"):
        assert ra[k] == rb[k], k
    other = make_photo_benchmark(tmp_path / "seed1", TINY.override(seed=1), progress=False)
    assert other["photos"][0]["room_seed"] != ra["room_seed"]


@pytest.mark.mitsuba
def test_prior_ceiling_and_start_rows_split_the_gap(built, tmp_path, monkeypatch):
    from roomlight.prior.model import Normalization, PanoVAE
    from roomlight.prior.model.config import get_preset
    from roomlight.evaluation.photobench import adapter, ceiling
    from roomlight.evaluation.photobench.report import write_photo_report
    from roomlight.evaluation.photobench.runner import run_photo_benchmark

    torch.manual_seed(0)
    prior = PanoVAE(get_preset("tiny"), Normalization((0.5, 0.5, 0.5, 0.7), (0.6, 0.6, 0.6, 0.5))).eval()
    monkeypatch.setattr(ceiling, "CEILING_FIT", {"steps": 20, "init_from_encoder": True, "depth_weight": 3.0})
    calls = []
    stand_in = _stand_in_fit(calls)

    def fit(case_dir, method, preset, out_dir, model=None, progress=False, overrides=None):
        return stand_in(case_dir, "prior" if method.startswith("prior") else method, preset, out_dir)

    res = tmp_path / "res"
    methods = ("prior-samples", "prior", "prior-ceiling", "oracle")
    summary = run_photo_benchmark(built, res, methods, preset="fast", model=prior, eval_spp=8, fit=fit,
                                  progress=False)
    assert not summary.failed, summary.failed
    ceil = json.loads((res / "cases/photo-00000/prior-ceiling/result.json").read_text())
    assert ceil["emitter_kind"] == "mesh" and ceil["recovered_resolution"] == [16, 32] and ceil["materials"] is None
    assert "fit" not in ceil["files"]                        # a reference: nothing fitted from the photo
    md = write_photo_report(res, figures=False, progress=False)["markdown"].read_text()
    assert "**prior-ceiling − oracle**" in md and "**prior-samples − prior-ceiling**" in md
    gap = json.loads((res / "report" / "summary.json").read_text())["gap_steps"]
    step = next(g for g in gap if g["method"] == "prior-ceiling")
    assert set(step["paired"]) == {"oracle"}                 # each step pairs exactly its two rows
    summary = json.loads((res / "report" / "summary.json").read_text())
    assert "prior-ceiling" not in summary["paired"]["probes"]
    assert summary["probes_outside"]["oracle"]["outside"] == 0 and summary["probes_outside"]["oracle"]["probes"] >= 1

    # the start variants are fit-photo's prior with --init fixed
    seen = {}

    def fake_fit_photo(case, method, config, model=None, out_dir=None, progress=False):
        seen.update(method=method, init=config.init)
        raise RuntimeError("stop here")

    from roomlight.fitting.photo import fitter as fitter_mod

    monkeypatch.setattr(fitter_mod, "fit_photo", fake_fit_photo)
    with pytest.raises(RuntimeError, match="stop here"):
        adapter.fit_photo_case(_case(built), "prior-zero", "fast", tmp_path / "f")
    assert seen == {"method": "prior", "init": "zero"}


@pytest.mark.mitsuba
def test_probes_outside_a_small_light_are_counted_and_none_inside_a_large_one(built):
    from roomlight.core.light import Light
    from roomlight.evaluation.photobench.scoring import load_truth, oracle_light, probes_outside

    truth = load_truth(_case(built))
    oracle = oracle_light(_case(built), "mesh", truth)
    rad = np.ones((8, 16, 3), np.float32)

    def light(depth):
        return Light(rad, np.full((8, 16), depth, np.float32), "mesh", oracle.frame)

    # the probes stand within a few metres of the oracle centre, the light's origin
    tiny = probes_outside(truth, light(0.01), given_depth=False)
    assert set(tiny) == {str(p.label) for p in truth.probes} and all(v == 1.0 for v in tiny.values())
    assert all(v == 0.0 for v in probes_outside(truth, light(1000.0), given_depth=False).values())
    assert probes_outside(truth, Light(rad, None, "envmap", oracle.frame)) == {}
    # a probe straddling the light's surface is partly outside: put the surface at its centre's distance
    p = truth.probes[0]
    centre = oracle.frame @ np.linalg.inv(truth.camera.matrix) @ np.append(p.center, 1.0)
    share = probes_outside(truth, light(float(np.linalg.norm(centre[:3]))), given_depth=False)[str(p.label)]
    assert 0.2 < share < 0.8


@pytest.mark.mitsuba
def test_inserted_objects_have_their_truth_and_the_oracle_composites_them_better_than_a_naive_paste(built):
    """truth/insert.exr is the photo wherever the new objects change nothing (same seed and samples),
    and under the oracle light differential rendering scores above pasting the objects lit alone."""
    from roomlight.evaluation.photobench import case as fmt
    from roomlight.evaluation.photobench.insertion import composite_for_light, insertion_scores, naive_light, read_insert_truth
    from roomlight.evaluation.photobench.roomscene import RoomScenes
    from roomlight.evaluation.photobench.scoring import load_truth, oracle_light
    from roomlight.evaluation.photobench.tracing import trace_image
    from roomlight.datagen.synth.rooms import generate_room

    case = _case(built)
    image, labels, objects = read_insert_truth(case / fmt.TRUTH, clean=False)
    assert [o.label for o in objects] == [101, 102] and all((labels == o.label).sum() > 0 for o in objects)
    photo = fmt.read_rgb_exr(case / fmt.IMAGE)
    record = json.loads((case / fmt.RECORD).read_text())
    truth = load_truth(case)

    # The claim, render by render: the room again from its seed, traced from the photo's camera with the photo's
    # seed and sample count, times its exposure (trace_image is bit-deterministic for a seed).
    scenes = RoomScenes(generate_room(record["room_seed"]), TINY.max_depth)
    own = {o.id: o.mitsuba_mesh() for o in truth.objects}

    def photo_render(extra: dict) -> np.ndarray:
        img = trace_image(scenes.scene({**own, **extra}), truth.camera, TINY.spp, record["seeds"]["photo"])
        return (img * record["exposure"]).astype(np.float32)

    # the truth is that render with the new objects in place, bit for bit
    assert np.array_equal(photo_render({o.id: o.mitsuba_mesh() for o in objects}), image)
    # and with the same objects 20 m below the floor, outside the closed room where no path can meet them, that
    # render is the photo at every pixel: the samples are the photo's. Not always bit for bit: the objects change
    # the acceleration structure, which may settle a ray that meets two triangles exactly on their shared edge on
    # the other one, moving a hit by an ulp (seen: 1 pixel of 6912, 2.5e-7); hence float32 rounding, 1e-6.
    away = {o.id: replace(o, translate=(o.translate[0], o.translate[1] - 20.0, o.translate[2])).mitsuba_mesh()
            for o in objects}
    np.testing.assert_allclose(photo_render(away), photo, rtol=1e-6, atol=0)
    assert not (image == photo).all(-1)[labels > 0].any()  # every sample of an object's whole pixel meets it: new
    mats = {k: m.to_dict() for k, m in truth.materials.items()}
    oracle = composite_for_light(case, oracle_light(case, "mesh", truth), mats, objects, truth.camera, spp=32)
    naive = composite_for_light(case, naive_light(case), mats, objects, truth.camera, spp=32, local_scene=False)
    s_oracle = insertion_scores(oracle, image, labels, objects, truth.camera.matrix)
    s_naive = insertion_scores(naive, image, labels, objects, truth.camera.matrix)
    assert all(s["visible"] and s["region_pixels"] > s["object_pixels"] > 0 for s in s_oracle)
    assert np.mean([s["psnr_ldr"] for s in s_oracle]) > np.mean([s["psnr_ldr"] for s in s_naive]) + 1.0
    # outside the objects the naive paste leaves the photo as it is
    np.testing.assert_allclose(naive[labels == 0][:50], np.maximum(photo[labels == 0][:50], 0), atol=1e-5)


@pytest.mark.mitsuba
def test_stratified_inserts_spread_over_distance_and_height_away_from_the_probes(tmp_path):
    """--inserts-at stratified: one new object per stratum, the near one nearer than the middle one
    nearer than the far one, the raised one above the floor, none on a probe's footprint, each visible."""
    import json

    from roomlight.evaluation.photobench.builder import make_photo_benchmark
    from roomlight.evaluation.photobench.scoring import load_truth

    cfg = TINY.override(inserts=4, insert_placement="stratified", seed=400100)
    make_photo_benchmark(tmp_path / "b", cfg, progress=False)
    d = tmp_path / "b" / "photo-00000"
    info = json.loads((d / "truth" / "insert.json").read_text())
    truth = load_truth(d)
    strata = info["strata"]
    objs = {o["id"]: o for o in info["objects"]}
    assert list(strata.values())[:3] == ["near", "middle", "far"], strata
    eye = truth.camera.origin
    dist = {s: np.linalg.norm(np.asarray(objs[k]["translate"]) - eye) for k, s in strata.items()}
    assert dist["near"] < dist["middle"] < dist["far"], dist
    floor = min(o["translate"][1] for o in objs.values())
    if "raised" in dist:
        raised = next(k for k, s in strata.items() if s == "raised")
        assert objs[raised]["translate"][1] > floor + 0.1
    for o in objs.values():
        for p in truth.probes:  # clear of every probe
            gap = np.hypot(o["translate"][0] - p.center[0], o["translate"][2] - p.center[2])
            assert gap > p.radius + o["size"][0], (o["id"], p.id)
        assert info["pixels"][str(o["label"])] >= cfg.min_pixels
    # the default keeps the original placement: at the probes, no strata recorded
    assert PhotoBenchConfig().insert_placement == "probes"


@pytest.mark.mitsuba
def test_the_estimate_rows_read_the_photo_alone_with_the_camera_at_the_light_s_centre(built, tmp_path):
    """``estimate`` on a photo case: the bundled prior's light from the image, its frame the camera's tilt with
    no shift (the camera at the light's centre), probes scored, no materials and nothing inserted."""
    from roomlight.core.io import read_panorama
    from roomlight.demo import bundled_prior_path
    from roomlight.evaluation.photobench.runner import run_photo_benchmark
    from roomlight.fitting.photo.camera import camera_rotation
    from roomlight.fitting.photo.case import load_photo
    from roomlight.prior.model.runs import load_run_model

    prior = load_run_model(bundled_prior_path(), device="cpu")
    res = tmp_path / "res"
    summary = run_photo_benchmark(built, res, ("estimate",), preset="fast", model=prior, eval_spp=4, progress=False)
    assert not summary.failed, summary.failed
    rec = json.loads((res / "cases/photo-00000/estimate/result.json").read_text())
    assert rec["materials"] is None and rec["insertion"] is None and "fit" not in rec["files"]
    assert all(np.isfinite(rec["probes"][m]["psnr_ldr"]) for m in rec["probes"])
    frame = np.asarray(read_panorama(res / "cases/photo-00000/estimate/recovered.exr").metadata["light_from_camera"])
    case = load_photo(str(_case(built)))
    np.testing.assert_allclose(frame[:3, :3], camera_rotation(case.pitch_deg, case.roll_deg), atol=1e-6)
    np.testing.assert_allclose(frame[:3, 3], 0.0, atol=1e-9)
    # the depth-optional row needs a prior that has that encoder: the bundled one has none, one line says so
    failed = run_photo_benchmark(built, res, ("estimate-depth-optional",), preset="fast", model=prior, eval_spp=4,
                                 progress=False).failed
    assert len(failed) == 1 and "depth-optional view encoder" in next(iter(failed.values())), failed
