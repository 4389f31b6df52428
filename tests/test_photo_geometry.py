"""Photographs as geometry: intrinsics, depth unprojection, the depth mesh, object masks, photo cases,
the frustum and repulsion terms, the placement of the scene, estimator adapters."""

from __future__ import annotations

import json
import math
from collections import deque

import numpy as np
import pytest
import torch

from roomlight.core.color import linear_to_srgb, srgb_to_linear
from roomlight.errors import InputFileError, RoomlightError
from roomlight.fitting.photo.camera import PhotoCamera, camera_rotation
from roomlight.fitting.photo.masks import connected_components, labels_from_array, read_mask, resize_nearest
from roomlight.fitting.photo.unproject import image_mesh, object_mesh, radial_distance, unproject

INTRINSICS = {
    "fov": PhotoCamera.from_fov(70.0, 40, 30),
    # off-centre principal point and non-square pixels: unprojection supports both
    "fx,fy,cx,cy": PhotoCamera(40, 30, 31.0, 36.5, 17.25, 19.5),
}


def _plane_depth(k: PhotoCamera, normal, offset, kind):
    """Depth of the plane n . p = offset seen through every pixel centre, computed from the ray
    parametrisation directly (not through unproject)."""
    n = np.asarray(normal, dtype=np.float64)
    n /= np.linalg.norm(n)
    u = np.arange(k.width) + 0.5
    v = np.arange(k.height) + 0.5
    uu, vv = np.meshgrid(u, v)
    x, y = (uu - k.cx) / k.fx, -(vv - k.cy) / k.fy
    denom = n[0] * x + n[1] * y - n[2]                   # n . (x, y, -1)
    z_depth = offset / denom                              # p = Z (x, y, -1)
    radial = z_depth * np.sqrt(x * x + y * y + 1.0)
    return (z_depth if kind == "z" else radial), n


@pytest.mark.parametrize("form", list(INTRINSICS))
@pytest.mark.parametrize("kind", ["z", "radial"])
def test_unprojection_puts_every_pixel_on_the_analytic_plane(form, kind):
    k = INTRINSICS[form]
    for normal, offset in [((0, 0, 1), -2.5), ((0.3, 0.4, 0.85), -1.7), ((-0.3, 0.2, 1.0), -3.0)]:
        depth, n = _plane_depth(k, normal, offset, kind)
        assert (depth > 0).all()
        p = unproject(depth, k, kind)
        assert np.abs(p @ n - offset).max() < 1e-9
        # and back onto the pixel centres it came from
        u = k.cx + k.fx * p[..., 0] / -p[..., 2]
        v = k.cy - k.fy * p[..., 1] / -p[..., 2]
        uu, vv = np.meshgrid(np.arange(k.width) + 0.5, np.arange(k.height) + 0.5)
        assert np.abs(u - uu).max() < 1e-9 and np.abs(v - vv).max() < 1e-9
        if kind == "z":
            assert np.abs(-p[..., 2] - depth).max() < 1e-9
        else:
            assert np.abs(np.linalg.norm(p, axis=-1) - depth).max() < 1e-9
            assert np.abs(radial_distance(depth, k, "radial") - depth).max() < 1e-9


def test_fronto_parallel_plane_in_radial_depth_bends_as_expected():
    # A wall 2 m ahead: radial depth grows as 2 / cos(angle off axis).
    k = INTRINSICS["fov"]
    z = np.full((k.height, k.width), 2.0)
    r = radial_distance(z, k, "z")
    assert r.min() > 2.0 and abs(float(r[k.height // 2, k.width // 2]) - 2.0) < 0.02
    corner = math.sqrt(((0.5 - k.cx) / k.fx) ** 2 + ((0.5 - k.cy) / k.fy) ** 2 + 1.0)
    assert abs(float(r[0, 0]) - 2.0 * corner) < 1e-9


def test_intrinsics_forms_and_their_errors():
    k = PhotoCamera.from_fov(90.0, 200, 100)
    assert k.fx == pytest.approx(100.0) and (k.cx, k.cy) == (100.0, 50.0) and k.fov_x == pytest.approx(90.0)
    half = k.scaled(100, 50)
    assert (half.fx, half.cx, half.cy) == pytest.approx((50.0, 50.0, 25.0))
    assert PhotoCamera.parse("1,2,3,4", 10, 10).intrinsics_dict() == {"fx": 1.0, "fy": 2.0, "cx": 3.0, "cy": 4.0}
    for bad in ["1,2,3", "a,b,c,d", "0,1,1,1"]:
        with pytest.raises(RoomlightError):
            PhotoCamera.parse(bad, 10, 10)
    with pytest.raises(RoomlightError, match="square pixels"):
        PhotoCamera(10, 10, 100, 103, 5, 5).check_square_pixels()
    PhotoCamera(10, 10, 100, 100.5, 5, 5).check_square_pixels()  # within 1 %
    with pytest.raises(RoomlightError, match="field of view"):
        PhotoCamera.from_fov(180.0, 10, 10)


def test_camera_rotation_pitch_and_roll():
    assert np.allclose(camera_rotation(0, 0), np.eye(3))
    r = camera_rotation(30.0, 0.0)
    assert np.allclose(r @ [0, 0, -1], [0, math.sin(math.radians(30)), -math.cos(math.radians(30))])  # looks up
    r = camera_rotation(0.0, 90.0)
    assert np.allclose(r @ [0, 1, 0], [-1, 0, 0])  # image up turns to the left: counter-clockwise roll
    r = camera_rotation(-20.0, 15.0)
    assert np.allclose(r @ r.T, np.eye(3)) and np.linalg.det(r) == pytest.approx(1.0)


@pytest.mark.mitsuba
def test_pinhole_sensor_sees_the_pixel_rays_of_the_intrinsics(mi):
    """Mitsuba's camera built from (fx, cx, cy) shoots, through each pixel centre, the ray the
    unprojection uses (off-centre principal point, level and tilted camera)."""
    from roomlight.fitting.photo.geometry import SceneTransform
    from roomlight.fitting.photo.scene import photo_sensor

    k = PhotoCamera(40, 30, 30.0, 30.0, 17.25, 12.5)
    for pitch, roll in [(0.0, 0.0), (-25.0, 10.0)]:
        t = SceneTransform(camera_rotation(pitch, roll), 1.0, np.array([0.3, 1.2, -0.4]))
        sensor = mi.load_dict(photo_sensor(k, t))
        uu, vv = np.meshgrid((np.arange(k.width) + 0.5) / k.width, (np.arange(k.height) + 0.5) / k.height)
        ray, _ = sensor.sample_ray(0.0, 0.5, mi.Point2f(uu.ravel(), vv.ravel()), mi.Point2f(0.5, 0.5))
        d = np.stack([np.array(ray.d.x), np.array(ray.d.y), np.array(ray.d.z)], -1)
        expected = t.directions(k.pixel_rays().reshape(-1, 3))
        expected /= np.linalg.norm(expected, axis=1, keepdims=True)
        assert np.abs(d - expected).max() < 1e-5, (pitch, roll)
        o = np.stack([np.array(ray.o.x), np.array(ray.o.y), np.array(ray.o.z)], -1)
        assert np.abs(np.cross(o - [0.3, 1.2, -0.4], d)).max() < 1e-5  # rays start on the camera centre's line


# ---------------------------------------------------------------------------------------- the depth mesh
def test_depth_mesh_of_a_plane_keeps_every_triangle_facing_the_camera():
    k = INTRINSICS["fx,fy,cx,cy"]
    depth, n = _plane_depth(k, (0.2, 0.3, 0.9), -1.5, "z")
    mesh = image_mesh(depth, k, "z")
    h, w = depth.shape
    assert len(mesh.faces) == 2 * (h - 1) * (w - 1)
    v = mesh.vertices
    fn = np.cross(v[mesh.faces[:, 1]] - v[mesh.faces[:, 0]], v[mesh.faces[:, 2]] - v[mesh.faces[:, 0]])
    centre = v[mesh.faces].mean(1)
    assert (np.einsum("ij,ij->i", fn, -centre) > 0).all()  # towards the camera at the origin
    obj = object_mesh(mesh, np.ones((h, w), int), 1)
    facing = n if np.dot(n, -v.mean(0)) > 0 else -n
    assert np.abs(obj.normals - facing).max() < 1e-9


def test_depth_mesh_cuts_triangles_across_a_depth_step():
    k = PhotoCamera.from_fov(30.0, 12, 8)  # 2.5 degrees per pixel: the flat parts change by < 1.5 % per pixel
    depth = np.full((8, 12), 2.0)
    depth[:, 7:] = 3.0  # a step between columns 6 and 7
    mesh = image_mesh(depth, k, "z", edge_tolerance=0.05)
    assert len(mesh.faces) == 2 * 7 * 11 - 2 * 7  # the seven quads spanning the step are gone
    cols = mesh.faces % 12
    assert not ((cols.min(1) <= 6) & (cols.max(1) >= 7)).any()


def test_object_mesh_is_cut_to_its_label_and_reindexed():
    k = PhotoCamera.from_fov(60.0, 10, 10)
    mesh = image_mesh(np.full((10, 10), 2.0), k, "radial")
    labels = np.zeros((10, 10), int)
    labels[2:5, 3:7] = 4
    labels[7:, :] = 9
    obj = object_mesh(mesh, labels, 4)
    assert obj.label == 4 and len(obj.vertices) == 12 and len(obj.faces) == 2 * 2 * 3
    assert set(obj.pixels.tolist()) == {i * 10 + j for i in range(2, 5) for j in range(3, 7)}
    assert obj.faces.max() == len(obj.vertices) - 1
    with pytest.raises(RoomlightError, match="no triangle"):
        object_mesh(mesh, labels, 5)


# ---------------------------------------------------------------------------------------- masks
def _bfs_components(fg: np.ndarray) -> list[set]:
    h, w = fg.shape
    seen = np.zeros_like(fg)
    comps = []
    for i in range(h):
        for j in range(w):
            if fg[i, j] and not seen[i, j]:
                comp, queue = set(), deque([(i, j)])
                seen[i, j] = True
                while queue:
                    a, b = queue.popleft()
                    comp.add((a, b))
                    for da in (-1, 0, 1):
                        for db in (-1, 0, 1):
                            x, y = a + da, b + db
                            if 0 <= x < h and 0 <= y < w and fg[x, y] and not seen[x, y]:
                                seen[x, y] = True
                                queue.append((x, y))
                comps.append(comp)
    return comps


def test_connected_components_match_a_breadth_first_search():
    rng = np.random.default_rng(3)
    for density in (0.2, 0.45, 0.6):
        fg = rng.random((23, 31)) < density
        labels, n = connected_components(fg)
        comps = _bfs_components(fg)
        assert n == len(comps)
        for k, comp in enumerate(comps, start=1):  # BFS finds them in reading order too
            assert {tuple(p) for p in np.argwhere(labels == k)} == comp
    spiral = np.zeros((15, 15), bool)
    spiral[1, 1:14] = spiral[1:14, 13] = spiral[13, 1:14] = spiral[3:14, 1] = spiral[3, 1:12] = True
    assert connected_components(spiral)[1] == 1


def test_mask_kinds_binary_labels_colours_and_small_objects(tmp_path):
    from PIL import Image

    binary = np.zeros((20, 20), np.uint8)
    binary[2:6, 2:6] = 255
    binary[10:15, 12:18] = 255
    lab = labels_from_array(binary)
    assert lab.kind == "binary" and lab.ids == [1, 2] and (lab.labels[3, 3], lab.labels[12, 14]) == (1, 2)
    ints = np.zeros((20, 20), np.uint16)
    ints[2:6, 2:6] = 7
    ints[10:15, 12:18] = 300
    ints[0, 19] = 7  # not touching: still object 7
    lab = labels_from_array(ints)
    assert lab.kind == "labels" and lab.ids == [7, 300] and lab.labels[0, 19] == 7
    colours = np.zeros((20, 20, 3), np.uint8)
    colours[10:15, 12:18] = (0, 200, 0)
    colours[2:6, 2:6] = (255, 0, 0)
    lab = labels_from_array(colours)
    assert lab.kind == "colours" and lab.ids == [1, 2] and lab.labels[3, 3] == 1 and lab.labels[12, 14] == 2
    tiny = binary.copy()
    tiny[18, 0] = 255
    lab = labels_from_array(tiny, min_fraction=0.01)  # 4 pixels of 400 = 1 %: the single pixel goes
    assert lab.ids == [1, 2] and lab.notes and "ignored 1 object" in lab.notes[0]
    # files: 8-bit, 16-bit and palette PNG, .npy
    Image.fromarray(ints).save(tmp_path / "m16.png")
    assert read_mask(tmp_path / "m16.png").ids == [7, 300]
    np.save(tmp_path / "m.npy", ints.astype(np.int32))
    assert read_mask(tmp_path / "m.npy").ids == [7, 300]
    pal = Image.fromarray((ints > 0).astype(np.uint8) * 3, mode="P")
    pal.save(tmp_path / "p.png")
    assert read_mask(tmp_path / "p.png").kind == "binary"
    with pytest.raises(RoomlightError, match="selects no pixel"):
        labels_from_array(np.zeros((4, 4), np.uint8))
    (tmp_path / "m.jpg").write_bytes(b"not a png")
    with pytest.raises(InputFileError, match="JPEG"):
        read_mask(tmp_path / "m.jpg")


def test_nearest_resampling_takes_the_pixel_under_each_centre():
    a = np.arange(12).reshape(3, 4)
    assert np.array_equal(resize_nearest(a, 3, 4), a)
    assert np.array_equal(resize_nearest(a, 6, 8)[::2, ::2], a)
    assert np.array_equal(resize_nearest(np.arange(6).reshape(2, 3), 1, 1), [[4]])


def test_srgb_transfer_function():
    assert srgb_to_linear(np.array([0.0, 1.0]))[1] == pytest.approx(1.0)
    assert float(srgb_to_linear(np.array(0.5))) == pytest.approx(0.21404, abs=1e-5)
    assert float(srgb_to_linear(np.array(0.04))) == pytest.approx(0.04 / 12.92)
    x = np.linspace(0, 1, 101)
    assert np.abs(linear_to_srgb(srgb_to_linear(x)) - x).max() < 1e-12


# ---------------------------------------------------------------------------------------- photo cases
def _write_case(folder, size=(24, 32), kind="z"):
    from roomlight.fitting.photo.case import write_photo_case

    h, w = size
    k = PhotoCamera.from_fov(60.0, w, h)
    depth, _ = _plane_depth(k, (0, 0.3, 1), -2.0, kind)
    labels = np.zeros((h, w), np.int32)
    labels[5:15, 6:14] = 1
    labels[12:20, 18:28] = 2
    img = np.random.default_rng(0).random((h, w, 3)).astype(np.float32) * 0.8
    write_photo_case(folder, img, depth.astype(np.float32), labels, k, depth_kind=kind)
    return img, depth, labels, k


def test_photo_case_round_trip(tmp_path):
    from roomlight.fitting.photo.case import load_photo

    img, depth, labels, k = _write_case(tmp_path / "case", kind="z")
    case = load_photo(tmp_path / "case")
    assert np.array_equal(case.image, img) and np.allclose(case.depth, depth, rtol=1e-6)
    assert np.array_equal(case.objects.labels, labels) and case.objects.ids == [1, 2]
    assert case.depth_kind == "z" and case.intrinsics == k
    cam = json.loads((tmp_path / "case" / "camera.json").read_text())
    assert cam["format"] == "roomlight.photo-case" and cam["intrinsics"]["fx"] == pytest.approx(k.fx)
    # options override the folder's camera.json
    case = load_photo(tmp_path / "case", fov=90.0, depth_kind="radial", pitch=-10)
    assert case.intrinsics.fov_x == pytest.approx(90.0) and case.depth_kind == "radial" and case.pitch_deg == -10


def test_photo_image_files_srgb_png_and_linear_exr(tmp_path):
    from PIL import Image

    from roomlight.core.io import write_exr
    from roomlight.fitting.photo.case import read_image

    rgb8 = np.array([[[0, 128, 255], [64, 64, 64]]], np.uint8)
    Image.fromarray(rgb8).save(tmp_path / "a.png")
    img, _ = read_image(tmp_path / "a.png")
    assert np.allclose(img, srgb_to_linear(rgb8 / 255.0), atol=1e-7)
    lin = np.array([[[0.1, 2.5, 0.0]]], np.float32)
    write_exr(tmp_path / "b.exr", {c: lin[..., i] for i, c in enumerate("RGB")})
    img, _ = read_image(tmp_path / "b.exr")
    assert np.array_equal(img, lin)


# ---------------------------------------------------------------------------------------- terms by hand
def test_frustum_terms_by_hand():
    from roomlight.fitting.photo.frustum import FrustumTarget, frustum_terms

    h, w = 8, 16
    radiance = torch.full((h, w, 3), 0.4)
    depth = torch.full((h, w), 3.0)
    pts = np.array([[0.0, 0.0, -1.5], [2.0, 0.0, 0.0], [0.0, 0.0, 6.0]])   # |q| = 1.5, 2, 6
    obs = np.array([[0.4, 0.4, 0.4], [0.2, 0.3, 0.5], [1.0, 0.5, 0.5]])   # the third is saturated
    t = FrustumTarget(pts, pts / np.linalg.norm(pts, axis=1, keepdims=True), obs)
    out = frustum_terms(radiance, depth, t, tau=0.99, c_max=10.0, lambda_log=0.01, log_eps=1e-3)
    l2 = (0 + (0.2 ** 2 + 0.1 ** 2 + 0.1 ** 2) + (0.6 ** 2 + 0.1 ** 2 + 0.1 ** 2)) / 3
    lg = sum((math.log(a + 1e-3) - math.log(b + 1e-3)) ** 2 for a, b in
             [(0.4, 0.2), (0.4, 0.3), (0.4, 0.5), (0.4, 1.0), (0.4, 0.5), (0.4, 0.5)]) / 3
    assert float(out["frustum"]) == pytest.approx(l2 + 0.01 * lg, rel=1e-5)
    dl = [(math.log(3.0) - math.log(r)) ** 2 for r in (1.5, 2.0, 6.0)]
    assert float(out["frustum_depth"]) == pytest.approx(sum(dl) / 3, rel=1e-5)
    # an env map: radiance along the rays only, no depth term
    out = frustum_terms(radiance, None, t)
    assert set(out) == {"frustum"}


def test_repulsion_with_frustum_points_by_hand():
    """Object points and free-space points of the view frustum count alike: mean over all of
    max(m - (D - |q|), 0) against a room of constant depth D."""
    from roomlight.fitting.inverse.repulsion import repulsion_penalty

    depth = torch.full((16, 32), 2.0)
    objects = torch.tensor([[0.0, -0.5, -1.0], [0.0, 0.0, -1.95]])            # |q| = 1.118, 1.95
    free = torch.tensor([[0.3, 0.0, -0.4], [0.0, 0.0, -2.2]])                # |q| = 0.5, 2.2 (beyond the wall)
    m = 0.1
    expected = np.mean([max(m - (2.0 - r), 0.0) for r in (math.hypot(0.5, 1.0), 1.95, 0.5, 2.2)])
    got = float(repulsion_penalty(depth, torch.cat([objects, free]), m))
    assert got == pytest.approx(expected, rel=1e-5)
    assert expected == pytest.approx((0.05 + 0.3) / 4)


def test_free_space_points_lie_between_the_camera_and_the_surfaces():
    from roomlight.fitting.photo.case import load_photo
    from roomlight.fitting.photo.config import photo_config
    from roomlight.fitting.photo.geometry import build_geometry

    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as d:
        _write_case(Path(d) / "case", kind="radial")
        case = load_photo(Path(d) / "case")
    cfg = photo_config("fast", frustum_points=300, render_size=32, geometry_size=32, repulsion_points=50)
    g = build_geometry(case, cfg)
    # every free point lies on a pixel ray at most 90 % of the way to the plane n . p = -2
    n = np.array([0, 0.3, 1.0]) / np.linalg.norm([0, 0.3, 1.0])
    frac = (g.free_points @ n) / -2.0
    assert len(g.free_points) == 300 and frac.min() > 0 and frac.max() <= 0.9 + 1e-9
    assert len(g.object_points) == 100
    assert g.loss_mask.sum() > 0 and not (g.loss_mask & (g.labels == 0)).any()
    assert np.abs(g.frustum.points @ n + 2.0).max() < 1e-6  # the depth file is float32


def test_placement_recovers_a_known_scale_and_position():
    """Points of a box room seen from a known camera position, given in a scaled camera frame, are
    put back where they belong by the frustum depth term."""
    from roomlight.core.geometry.analytic import box_distance, box_room_depth
    from roomlight.fitting.photo.placement import place_scene

    lo, hi = (-2.0, -1.5, -3.5), (3.0, 1.3, 1.5)
    depth = box_room_depth(64, 128, lo, hi)
    cam, scale = np.array([0.6, -0.3, 0.4]), 1.7
    rng = np.random.default_rng(0)
    dirs = rng.normal(size=(800, 3)) * [1, 0.6, 1] + [0, -0.3, -2.0]   # a forward-looking cone
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    t = box_distance(torch.from_numpy(dirs), lo, hi, origin=tuple(cam)).numpy()
    room_points = cam + dirs * t[:, None]
    camera_points = (room_points - cam) / scale
    placed = place_scene(depth.float(), np.eye(3), camera_points, camera_points[:50] * 0.5, margin=0.05,
                         steps=150, lr=0.05)
    assert placed.scale == pytest.approx(scale, rel=0.05)
    assert np.abs(placed.translation - cam).max() < 0.1


# ---------------------------------------------------------------------------------------- estimators
def stand_in_estimator(image):
    """A monocular estimator for the tests: a wall 2 m away seen with a 60 degree lens."""
    h, w = image.shape[:2]
    return np.full((h, w), 2.0, np.float32), (w / (2 * math.tan(math.radians(30))), w / (2 * math.tan(math.radians(30))),
                                                w / 2, h / 2)


def test_estimators_callable_module_function_and_moge_conversion(tmp_path):
    from roomlight.fitting.photo.case import load_photo
    from roomlight.fitting.photo.estimator import MoGeEstimator, as_estimate, resolve_estimator

    _write_case(tmp_path / "case")
    (tmp_path / "case" / "depth.exr").unlink()
    (tmp_path / "case" / "camera.json").write_text(json.dumps({"format": "roomlight.photo-case", "version": 1}))
    case = load_photo(tmp_path / "case", estimator=stand_in_estimator)
    assert case.intrinsics.fov_x == pytest.approx(60.0) and np.all(case.depth == 2.0)
    assert "estimated" in case.files["depth"]
    assert resolve_estimator("test_photo_geometry:stand_in_estimator") is stand_in_estimator
    with pytest.raises(RoomlightError, match="module:function"):
        resolve_estimator("nonsense")
    with pytest.raises(RoomlightError, match="depth of shape"):
        as_estimate((np.ones((3, 3)), None), 4, 3)
    # MoGe's output: OpenCV frame (y down, z forward), intrinsics normalised by the image size
    h, w = 6, 8
    out = {"depth": np.full((h, w), 3.0, np.float32), "mask": np.ones((h, w), bool),
           "intrinsics": np.array([[0.5, 0, 0.5], [0, 0.75, 0.45], [0, 0, 1]], np.float32),
           "normal": np.tile(np.array([0.0, -0.6, -0.8], np.float32), (h, w, 1))}
    out["depth"][0, 0] = np.inf
    out["mask"][1, 1] = False
    est = MoGeEstimator.convert(out, w, h)
    assert est.kind == "z" and (est.intrinsics.fx, est.intrinsics.fy, est.intrinsics.cx, est.intrinsics.cy) == \
        pytest.approx((4.0, 4.5, 4.0, 2.7))
    assert np.allclose(est.normals[2, 3], [0.0, 0.6, 0.8])       # up and towards the viewer in our frame
    assert est.depth[0, 0] == 3.0 and est.depth[1, 1] == 3.0      # invalid pixels take the largest valid depth


def _fake_moge(monkeypatch, weights: bool):
    """A stand-in ``moge`` package: MoGe-2's loading and inference interface over a wall 3 m away."""
    import importlib.machinery
    import sys
    import types

    calls = {}

    class FakeMoGe(torch.nn.Module):
        def __init__(self):
            super().__init__()
            self.w = torch.nn.Parameter(torch.zeros(1))

        @classmethod
        def from_pretrained(cls, name, **kwargs):
            calls["name"], calls["kwargs"] = name, kwargs
            if not weights:
                raise FileNotFoundError("no such file in the local cache")
            return cls()

        def infer(self, image, apply_mask=True, use_fp16=True):
            calls["image"] = image
            _, h, w = image.shape
            return {"depth": torch.full((h, w), 3.0), "mask": torch.ones(h, w, dtype=torch.bool),
                    "intrinsics": torch.tensor([[0.8, 0, 0.5], [0, 0.8 * w / h, 0.5], [0, 0, 1.0]]),
                    "normal": torch.tensor([0.0, 0.0, -1.0]).expand(h, w, 3)}

    for name in ("moge", "moge.model", "moge.model.v2"):
        mod = types.ModuleType(name)
        mod.__spec__ = importlib.machinery.ModuleSpec(name, None)
        monkeypatch.setitem(sys.modules, name, mod)
    sys.modules["moge.model.v2"].MoGeModel = FakeMoGe
    return calls


def test_moge_adapter_loads_local_weights_only_and_converts(tmp_path, monkeypatch):
    from roomlight.fitting.photo.case import load_photo

    _write_case(tmp_path / "case")
    (tmp_path / "case" / "depth.exr").unlink()
    (tmp_path / "case" / "camera.json").unlink()
    monkeypatch.delenv("ROOMLIGHT_MOGE_MODEL", raising=False)
    calls = _fake_moge(monkeypatch, weights=True)
    case = load_photo(tmp_path / "case" / "image.exr", mask=tmp_path / "case" / "mask.png")
    assert calls["name"] == "Ruicheng/moge-2-vitl-normal" and calls["kwargs"] == {"local_files_only": True}
    assert tuple(calls["image"].shape) == (3, 24, 32) and float(calls["image"].max()) <= 1.0  # sRGB in [0, 1]
    assert case.depth_kind == "z" and np.all(case.depth == 3.0)
    assert case.intrinsics.fx == pytest.approx(0.8 * 32) and case.intrinsics.cx == pytest.approx(16.0)
    assert np.allclose(case.normals, [0.0, 0.0, 1.0])  # facing the camera in roomlight's frame
    _fake_moge(monkeypatch, weights=False)
    with pytest.raises(RoomlightError, match=r"image.exr: the moge estimator cannot run: MoGe weights .* --depth FILE"):
        load_photo(tmp_path / "case" / "image.exr", mask=tmp_path / "case" / "mask.png", fov=60)
