"""A mesh cut to a photograph's view and textured by projection (roomlight.fitting.insert.view_mesh),
against analytic areas, a Monte Carlo count and the exact projection."""

from __future__ import annotations

import numpy as np
import pytest

from roomlight.errors import RoomlightError
from roomlight.fitting.insert.view_mesh import clip_to_view, frustum_planes, mesh_in_view, subdivide_in_view, view_uv
from roomlight.fitting.photo.camera import PhotoCamera

CAM = PhotoCamera(width=64, height=48, fx=50.0, fy=50.0, cx=30.0, cy=26.0)


def _area(v, f):
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    return 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1).sum()


def _quad(o, a, b):
    o, a, b = (np.asarray(x, np.float64) for x in (o, a, b))
    return np.stack([o, o + a, o + a + b, o + b]), np.array([[0, 1, 2], [0, 2, 3]])


def _inside(points, cam):
    z = -points[:, 2]
    x = cam.cx + cam.fx * points[:, 0] / z
    y = cam.cy - cam.fy * points[:, 1] / z
    return (z > 0) & (x >= 0) & (x <= cam.width) & (y >= 0) & (y <= cam.height)


def test_a_wall_facing_the_camera_is_cut_to_the_image_rectangle():
    v, f = _quad((-10, -10, -2), (20, 0, 0), (0, 20, 0))
    cv, cf = clip_to_view(v, f, frustum_planes(CAM, margin_px=0.0))
    # At distance 2 the image spans W / fx * 2 by H / fy * 2 metres.
    assert _area(cv, cf) == pytest.approx((64 / 50 * 2) * (48 / 50 * 2), rel=1e-9)
    uv = view_uv(cv, CAM)
    np.testing.assert_allclose(uv.min(0), [0, 0], atol=1e-9)
    np.testing.assert_allclose(uv.max(0), [1, 1], atol=1e-9)


def test_a_floor_running_behind_the_camera_keeps_the_area_a_monte_carlo_count_finds():
    v, f = _quad((-4, -1.2, 3), (8, 0, 0), (0, 0, -9))        # from behind the camera to 6 m in front
    cv, cf = clip_to_view(v, f, frustum_planes(CAM, margin_px=0.0))
    assert (-cv[:, 2] > 0).all()
    rng = np.random.default_rng(0)
    s = rng.random((400_000, 2))
    pts = np.stack([-4 + 8 * s[:, 0], np.full(len(s), -1.2), 3 - 9 * s[:, 1]], 1)
    expected = 72.0 * _inside(pts, CAM).mean()
    assert _area(cv, cf) == pytest.approx(expected, rel=0.01)
    assert 0.2 < _area(cv, cf) / 72.0 < 0.8


def test_a_triangle_wholly_outside_is_dropped_and_one_inside_is_kept_as_it_is():
    v = np.array([[0.0, 0.0, -3.0], [0.1, 0.0, -3.0], [0.0, 0.1, -3.0],      # inside
                  [0.0, 0.0, 3.0], [1.0, 0.0, 3.0], [0.0, 1.0, 3.0]])          # behind the camera
    cv, cf = clip_to_view(v, np.array([[0, 1, 2], [3, 4, 5]]), frustum_planes(CAM))
    assert len(cf) == 1
    np.testing.assert_array_equal(cv[cf[0]], v[:3])


def test_subdivision_keeps_the_area_brings_edges_under_the_bound_and_the_texture_onto_its_pixel():
    v, f = _quad((-4, -1.2, 3), (8, 0, 0), (0, 0, -9))
    cv, cf = clip_to_view(v, f, frustum_planes(CAM, margin_px=0.0))
    sv, sf = subdivide_in_view(cv, cf, CAM, max_edge_px=2.0)
    assert _area(sv, sf) == pytest.approx(_area(cv, cf), rel=1e-9)
    z = -sv[:, 2]
    px = np.stack([CAM.cx + CAM.fx * sv[:, 0] / z, CAM.cy - CAM.fy * sv[:, 1] / z], -1)[sf]
    assert np.linalg.norm(px - np.roll(px, -1, axis=1), axis=-1).max() <= 2.0 + 1e-9
    # A texture coordinate interpolated linearly across a small triangle lands within a tenth of a pixel
    # of where the point it belongs to is seen; across the unsplit triangles it does not.
    rng = np.random.default_rng(1)

    def worst(vv, ff):
        w = rng.dirichlet(np.ones(3), len(ff))
        p = np.einsum("tc,tcd->td", w, vv[ff])
        uv_lin = np.einsum("tc,tcd->td", w, view_uv(vv, CAM)[ff])
        return (np.abs(uv_lin - view_uv(p, CAM)) * [CAM.width, CAM.height]).max()

    assert worst(sv, sf) < 0.1
    assert worst(cv, cf) > 2.0


def test_mesh_in_view_returns_only_the_vertices_it_uses_and_refuses_points_behind_the_camera():
    v, f = _quad((-4, -1.2, 3), (8, 0, 0), (0, 0, -9))
    mv, mf, uv = mesh_in_view(v, f, CAM)
    assert len(np.unique(mf)) == len(mv) and uv.shape == (len(mv), 2)
    # one pixel of margin around the image
    assert uv[:, 0].min() >= -1.0 / CAM.width - 1e-9 and uv[:, 0].max() <= 1 + 1.0 / CAM.width + 1e-9
    with pytest.raises(RoomlightError, match="behind the camera"):
        subdivide_in_view(v, f, CAM)
