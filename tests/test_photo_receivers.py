"""Shadow receivers: which pixels around each object are its receiver, their meshes in the photo's
geometry, and their term in the photo fit's objective."""

from __future__ import annotations

from collections import deque

import numpy as np
import pytest
import torch

from roomlight.fitting.photo.camera import PhotoCamera, camera_rotation
from roomlight.fitting.photo.receivers import receiver_labels

UP = np.array([0.0, 1.0, 0.0])


def _reference_receivers(labels, candidate, radius, band=2):
    """The slow obvious version: for every object a breadth-first search (8-connected) from its pixels through
    candidate pixels and the background pixels within ``band`` steps of any object (the silhouette's depth
    edge, crossed but never taken); a candidate pixel goes to the object with the fewest steps, if within that
    object's reach
    (radius times its bounding box's larger side). Pixels two objects reach in the same number of steps are
    marked -1 (the tie rule is the implementation's choice)."""
    h, w = labels.shape
    yy, xx = np.mgrid[:h, :w]
    oy, ox = np.nonzero(labels)
    cheb = np.min(np.maximum(np.abs(yy[..., None] - oy), np.abs(xx[..., None] - ox)), axis=-1)
    passable = candidate | ((cheb <= band) & (labels == 0))
    best = np.full((h, w), np.inf)
    owner = np.zeros((h, w), np.int64)
    for lab in [int(v) for v in np.unique(labels) if v]:
        ys, xs = np.nonzero(labels == lab)
        reach = max(2, int(round(radius * max(np.ptp(ys) + 1, np.ptp(xs) + 1))))
        dist = np.full((h, w), np.inf)
        q = deque()
        for y, x in zip(ys, xs):
            dist[y, x] = 0
            q.append((y, x))
        while q:
            y, x = q.popleft()
            for dy in (-1, 0, 1):
                for dx in (-1, 0, 1):
                    v, u = y + dy, x + dx
                    if 0 <= v < h and 0 <= u < w and passable[v, u] and dist[v, u] == np.inf:
                        dist[v, u] = dist[y, x] + 1
                        q.append((v, u))
        dist[dist > reach] = np.inf
        dist[~candidate] = np.inf
        tie = (dist == best) & np.isfinite(dist)
        owner[tie] = -1
        closer = dist < best
        owner[closer] = lab
        best = np.minimum(best, dist)
    return owner


def test_receivers_match_a_breadth_first_search_through_upward_pixels():
    rng = np.random.default_rng(3)
    h, w = 40, 56
    labels = np.zeros((h, w), np.int32)
    labels[8:14, 6:12] = 1          # 6 px object: reach 3 (radius 0.5)
    labels[20:30, 30:36] = 2        # 10 px tall: reach 5
    labels[33:35, 8:10] = 3         # 2 px: reach max(2, 1) = 2
    normals = np.tile(UP, (h, w, 1))
    normals[:, 20:23] = [0.0, 0.0, 1.0]           # a wall strip facing the camera: no receiver crosses it
    ok = rng.random((h, w)) > 0.1                  # some unreliable normals (depth edges)
    got = receiver_labels(labels, normals, ok, UP, radius=0.5, min_up=0.7)
    candidate = ok & (normals @ UP >= 0.7) & (labels == 0)
    ref = _reference_receivers(labels, candidate, 0.5)
    decided = ref >= 0
    np.testing.assert_array_equal(got[decided], ref[decided])
    assert set(np.unique(got[~decided])) <= {1, 2, 3}    # a tie goes to one of the two
    assert not got[labels != 0].any() and not got[~candidate].any()
    assert not got[:, 20:23].any() and not (got[:, 23:] == 1).any()   # object 1 is left of the wall
    assert (got == 3).sum() > 0 and (got == 2).sum() > (got == 1).sum()


def test_receivers_follow_the_rooms_up_not_the_cameras():
    # A camera pitched down 30 degrees sees the floor with normals tilted towards it; the room's up in the
    # camera frame is what decides, so a floor pixel is a receiver and a wall pixel is not.
    r = camera_rotation(-30.0, 0.0)
    up_cam = r.T @ UP
    h, w = 20, 20
    labels = np.zeros((h, w), np.int32)
    labels[8:12, 8:12] = 1
    floor_normal = up_cam                                   # the floor's normal is the room's up
    wall_normal = r.T @ np.array([0.0, 0.0, 1.0])           # a wall facing the room's +z
    normals = np.tile(floor_normal, (h, w, 1))
    normals[:, :4] = wall_normal
    got = receiver_labels(labels, normals, np.ones((h, w), bool), up_cam, radius=1.0)
    assert (got[:, 4:] == 1).sum() > 0 and not got[:, :4].any()
    # with the camera's own up instead, the floor (tilted by 30 degrees, cos 0.87) still passes 0.7 but a
    # threshold of 0.9 rejects it: the room's up is the one that must be given
    assert not receiver_labels(labels, normals, np.ones((h, w), bool), UP, radius=1.0, min_up=0.9).any()


@pytest.fixture(scope="module")
def floor_case(tmp_path_factory):
    """A photo case of two spheres standing on a flat floor 1.2 m below a camera pitched down by 20 degrees
    (depth from the analytic floor plane and spheres, no rendering needed for the geometry)."""
    from roomlight.fitting.photo.case import load_photo, write_photo_case

    h, w = 48, 64
    k = PhotoCamera.from_fov(70.0, w, h)
    r = camera_rotation(-20.0, 0.0)
    u, v = np.meshgrid(np.arange(w) + 0.5, np.arange(h) + 0.5)
    rays_cam = np.stack([(u - k.cx) / k.fx, -(v - k.cy) / k.fy, -np.ones_like(u)], -1)
    rays = rays_cam @ r.T                               # room frame, camera at the origin
    t_floor = np.where(rays[..., 1] < -1e-6, -1.2 / np.minimum(rays[..., 1], -1e-6), 60.0)
    t = np.minimum(t_floor, 60.0)
    labels = np.zeros((h, w), np.int32)
    for lab, centre in ((1, (-0.5, -0.95, -2.2)), (2, (0.6, -0.95, -3.0))):
        c = np.asarray(centre)
        b = (rays * c).sum(-1)
        disc = b ** 2 - (c @ c - 0.25 ** 2) * (rays * rays).sum(-1)
        hit = (disc > 0) & (b > 0)
        ts = (b - np.sqrt(np.maximum(disc, 0))) / (rays * rays).sum(-1)
        closer = hit & (ts < t)
        t = np.where(closer, ts, t)
        labels[closer] = lab
    z_depth = t                                          # rays_cam has z = -1: t is the z-depth
    image = np.full((h, w, 3), 0.3, np.float32)
    folder = tmp_path_factory.mktemp("floor_case")
    write_photo_case(folder, image, z_depth.astype(np.float32), labels, k, pitch_deg=-20.0, depth_kind="z")
    return load_photo(folder)


def test_receiver_meshes_lie_on_the_floor_around_their_objects(floor_case):
    from roomlight.fitting.photo.config import photo_config
    from roomlight.fitting.photo.geometry import build_geometry, level_transform
    from roomlight.fitting.photo.receivers import shadow_receivers

    cfg = photo_config("fast", shadow_receivers=True)
    g = build_geometry(floor_case, cfg)
    r = shadow_receivers(g, floor_case, cfg)
    assert [m.label for m in r.meshes] == [1, 2]
    room = level_transform(floor_case)
    for m in r.meshes:
        p = room.points(m.vertices)
        assert np.abs(p[:, 1] + 1.2).max() < 1e-6            # on the floor plane
        n = room.directions(m.normals)
        assert (n[:, 1] > 0.999).all()                       # facing up
        obj = room.points(next(o for o in g.objects if o.label == m.label).vertices)
        centre = obj.mean(0)
        horizontal = np.linalg.norm((p - centre)[:, [0, 2]], axis=1)
        assert horizontal.min() < 0.5 and horizontal.max() < 2.0   # around its own sphere
    assert not (r.mask & (g.labels != 0)).any()
    assert r.mask.any()


def test_the_receivers_term_is_the_censored_image_loss_on_their_pixels(floor_case, tmp_path, one_torch_thread):
    """A short fit with receivers: result.json lists them, and the objective's receivers term equals the
    image loss recomputed by hand (numpy) from the final render over the receiver pixels."""
    import json

    from roomlight.fitting.inverse.fitter import EVAL_SEED_OFFSET
    from roomlight.fitting.inverse.lights import DirectLight
    from roomlight.fitting.photo.config import photo_config
    from roomlight.fitting.photo.fitter import fit_photo
    from roomlight.fitting.photo.outputs import write_fit_files

    cfg = photo_config("fast", shadow_receivers=True, iterations=2, spp=2, eval_spp=2, eval_every=1,
                       render_size=64, geometry_size=64, probe_count=0)
    light = DirectLight("envmap", (8, 16), init_radiance=0.4)
    fit = fit_photo(floor_case, "direct-envmap", cfg, light=light, progress=False, out_dir=tmp_path)
    assert "receivers" in fit.objective and fit.model.receivers is not None
    es = fit.fitter.escene
    with torch.no_grad():
        rad, depth = fit.model.emitter()
        es.set_emitter(rad, depth)
        es.set_parameters(fit.model.scene_values())
        img = es.render(spp=cfg.eval_spp, seed=cfg.seed + EVAL_SEED_OFFSET, sensor=fit.fitter.sensor).numpy()
    m = fit.fitter.receiver_mask.numpy()
    target = fit.fitter.target.numpy()
    r = img[m].astype(np.float64)
    tgt = target[m].astype(np.float64)
    sat = tgt.max(-1, keepdims=True) >= cfg.tau                      # censoring: a saturated pixel's render
    r = np.minimum(r, np.where(sat, 1.0, cfg.c_max))                  # counts up to 1, any other's up to c_max
    l2 = ((r - tgt) ** 2).sum() / m.sum()
    lg = ((np.log(np.maximum(r, 0) + cfg.log_eps) - np.log(tgt + cfg.log_eps)) ** 2).sum() / m.sum()
    assert fit.objective["receivers"] == pytest.approx(l2 + cfg.lambda_log * lg, rel=1e-4)
    paths = write_fit_files(tmp_path / "out", fit, floor_case, cfg)
    result = json.loads(paths["result"].read_text())
    rec = result["receivers"]
    assert [r["label"] for r in rec] == [1, 2]
    assert sum(r["fitted_pixels"] for r in rec) == int(fit.receivers.mask.sum())
    assert all(r["metallic"] < 1e-3 and r["roughness"] > 0.999 for r in rec)   # held: a diffuse floor
    # without asking, nothing changes: no receivers, no term
    plain = fit_photo(floor_case, "direct-envmap", cfg.override(shadow_receivers=False),
                      light=DirectLight("envmap", (8, 16), init_radiance=0.4), progress=False)
    assert plain.receivers is None and plain.model.receivers is None and "receivers" not in plain.objective
