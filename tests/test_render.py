"""Mitsuba-backed checks of the emitters against independent references."""

import math

import numpy as np
import pytest
import torch

from roomlight.core.geometry import box_room_depth, panorama_to_perspective, pixel_directions
from roomlight.core.emitter.area_light import build_area_light
from roomlight.core.render.bridge import render_differentiable
from roomlight.core.render.camera import perspective_sensor
from roomlight.core.render.scene import EmitterScene
from roomlight.core.render.variant import mitsuba

pytestmark = pytest.mark.mitsuba


def smooth_radiance(h, w):
    d = pixel_directions(h, w)
    x, y, z = d.unbind(-1)
    return torch.stack([1.5 + torch.sin(3 * x + 1) * torch.cos(2 * y), 1 + 0.8 * torch.sin(4 * z),
                        0.5 + 0.5 * y], -1).clamp(min=0)


def random_depth(h, w, lo=1.5, hi=4.0, seed=0):
    g = torch.Generator().manual_seed(seed)
    return lo + (hi - lo) * torch.rand(h, w, generator=g)


def wavy_depth(h, w):
    d = pixel_directions(h, w)
    return 2.5 + 0.6 * torch.sin(2 * d[..., 0]) * torch.cos(d[..., 2]) + 0.3 * d[..., 1]


def tonemap(x):
    return (x.clamp(min=0) / (1 + x.clamp(min=0))) ** (1 / 2.2)


def psnr(a, b, peak=1.0):
    return 10 * math.log10(peak**2 / float(((a - b) ** 2).mean()))


@pytest.mark.parametrize("depth_kind", ["random", "box", "constant"])
def test_camera_at_origin_sees_the_panorama(mi, depth_kind):
    h, w = 64, 128
    rad = smooth_radiance(h, w)
    depth = {"random": random_depth(h, w),
             "box": box_room_depth(h, w, (-2, -1.5, -3), (3, 1.2, 2)),
             "constant": torch.full((h, w), 2.0)}[depth_kind]
    for fwd, up in [((0, 0, -1), (0, 1, 0)), ((0.7, 0.2, 0.4), (0, 1, 0)), ((0.1, 1.0, 0.0), (0, 0, -1))]:
        es = EmitterScene("mesh", (h, w), sensor=perspective_sensor(target=fwd, up=up, fov_deg=75, width=64, height=48))
        es.set_emitter(rad, depth)
        img = es.render(spp=16)
        ref = panorama_to_perspective(rad.permute(2, 0, 1)[None], 48, 64, 75, forward=fwd, up=up)[0].permute(1, 2, 0)
        assert psnr(tonemap(img), tonemap(ref)) >= 35.0, (depth_kind, fwd)


@pytest.mark.parametrize("depth_kind", ["box", "wavy", "constant"])
def test_furnace_white_sphere_in_uniform_emitter(mi, depth_kind):
    h, w = 32, 64
    depth = {"box": box_room_depth(h, w, (-2, -1.5, -3), (3, 1.2, 2)), "wavy": wavy_depth(h, w),
             "constant": torch.full((h, w), 2.0)}[depth_kind]
    centre = [0.35, -0.25, -1.0]
    sphere = {"type": "sphere", "center": centre, "radius": 0.3,
              "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [1.0, 1.0, 1.0]}}}
    sens = perspective_sensor(origin=(0.1, 0.1, 0.2), target=centre, fov_deg=30, width=32, height=32)
    es = EmitterScene("mesh", (h, w), objects={"probe": sphere}, sensor=sens,
                      integrator={"type": "path", "max_depth": 4})
    es.set_emitter(torch.ones(h, w, 3), depth)
    img = es.render(spp=256)
    assert abs(float(img.mean()) - 1.0) < 0.02
    assert float((img.mean(-1) - 1.0).abs().max()) < 0.25  # no dark (back-facing) regions


# ----------------------------------------------------------------------------- quadrature
def bilinear_repeat(tex, uv):
    """Reference bilinear lookup with repeat wrap, texel centres at (j + 0.5) / W."""
    h, w, _ = tex.shape
    x = uv[:, 0] * w - 0.5
    y = uv[:, 1] * h - 0.5
    x0 = np.floor(x).astype(int)
    y0 = np.floor(y).astype(int)
    fx, fy = x - x0, y - y0
    def t(yy, xx):
        return tex[np.mod(yy, h), np.mod(xx, w)]
    return ((1 - fx)[:, None] * (1 - fy)[:, None] * t(y0, x0) + fx[:, None] * (1 - fy)[:, None] * t(y0, x0 + 1)
            + (1 - fx)[:, None] * fy[:, None] * t(y0 + 1, x0) + fx[:, None] * fy[:, None] * t(y0 + 1, x0 + 1))


def quadrature_irradiance(vertices, faces, uv, tex, x, n, sub=12):
    """E(x, n) = sum over triangles of L cos_e cos_x / r^2 dA, midpoint rule on sub^2 pieces."""
    bary = []
    for i in range(sub):
        for j in range(sub - i):
            bary.append(((i + 1 / 3) / sub, (j + 1 / 3) / sub))
            if i + j <= sub - 2:
                bary.append(((i + 2 / 3) / sub, (j + 2 / 3) / sub))
    b = np.array(bary)
    b = np.concatenate([b, 1 - b.sum(1, keepdims=True)], 1)  # (S, 3)
    p0, p1, p2 = (vertices[faces[:, k]] for k in range(3))
    cross = np.cross(p1 - p0, p2 - p0)
    area = 0.5 * np.linalg.norm(cross, axis=1)
    normal = cross / (2 * area[:, None])
    total = np.zeros(3)
    for s in range(len(b)):
        p = b[s, 0] * p0 + b[s, 1] * p1 + b[s, 2] * p2
        t = b[s, 0] * uv[faces[:, 0]] + b[s, 1] * uv[faces[:, 1]] + b[s, 2] * uv[faces[:, 2]]
        r = x[None] - p
        dist = np.linalg.norm(r, axis=1)
        rh = r / dist[:, None]
        cos_e = np.clip((normal * rh).sum(1), 0, None)
        cos_x = np.clip(-(rh * n[None]).sum(1), 0, None)
        L = bilinear_repeat(tex, t)
        total += (L * (cos_e * cos_x / dist**2 * area / len(b))[:, None]).sum(0)
    return total


def mitsuba_irradiance(es, spp=512):
    """Irradiance at x (normal n) = pi x radiance leaving a tiny white Lambertian patch there."""
    res = es.render(spp=spp)
    return math.pi * res.reshape(-1, 3).mean(0).double().numpy()


def irradiance_scene(kind, h, w, x, n):
    mi_ = mitsuba()
    x = np.asarray(x, float)
    n = np.asarray(n, float)
    up = [0, 0, 1] if abs(n[1]) > 0.9 else [0, 1, 0]
    patch = {"type": "rectangle",
             "to_world": mi_.ScalarTransform4f().look_at(origin=x.tolist(), target=(x + n).tolist(), up=up)
             @ mi_.ScalarTransform4f().scale([1e-3, 1e-3, 1.0]),
             "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [1.0, 1.0, 1.0]}}}
    sens = perspective_sensor(origin=(x + 0.05 * n).tolist(), target=x.tolist(), up=up, fov_deg=0.5, width=32, height=32)
    return EmitterScene(kind, (h, w), objects={"patch": patch}, sensor=sens,
                        integrator={"type": "path", "max_depth": 2})


def test_irradiance_matches_independent_quadrature(mi):
    h, w = 16, 32
    tex = torch.zeros(h, w, 3)
    tex[5:7, 20:22] = torch.tensor([40.0, 30.0, 20.0])  # one small bright patch
    depth = box_room_depth(h, w, (-2, -1.3, -2.5), (2.5, 1.4, 2))
    mesh = build_area_light(tex.double(), depth.double())
    V, F, UV = mesh.vertices.numpy(), mesh.faces.numpy(), mesh.uv.double().numpy()
    from roomlight.core.geometry import uv_to_direction
    # the patch's direction from the capture point; measure facing it from two points
    pdir = uv_to_direction(torch.tensor(21.0 / w, dtype=torch.float64), torch.tensor(6.0 / h, dtype=torch.float64)).numpy()
    points = [np.zeros(3), 0.5 * pdir + np.array([0.0, -0.2, 0.1])]
    quad, mits, envs = [], [], []
    for x in points:
        n = pdir.copy()
        q = quadrature_irradiance(V, F, UV, tex.double().numpy(), x, n)
        es = irradiance_scene("mesh", h, w, x, n)
        es.set_emitter(tex, depth)
        m = mitsuba_irradiance(es)
        ee = irradiance_scene("envmap", h, w, x, n)
        ee.set_emitter(tex)
        e = mitsuba_irradiance(ee)
        assert np.all(np.abs(m - q) / q < 0.03), (x, m, q)
        quad.append(q); mits.append(m); envs.append(e)
    ratio_q = quad[1] / quad[0]
    ratio_m = mits[1] / mits[0]
    assert ratio_q[0] > 1.3                 # closer to the light: noticeably brighter
    assert np.all(np.abs(ratio_m - ratio_q) / ratio_q < 0.04)
    assert np.all(np.abs(envs[1] - envs[0]) / envs[0] < 0.03)  # an env map has no parallax


def test_envmap_equals_distant_mesh_on_a_mirror_sphere(mi):
    h, w = 64, 128
    rad = smooth_radiance(h, w)
    mirror = {"type": "sphere", "center": [0.0, 0.0, -3.0], "radius": 1.0, "bsdf": {"type": "conductor"}}
    sens = perspective_sensor(target=(0, 0, -3), fov_deg=40, width=64, height=64)
    imgs = {}
    for kind, depth in [("mesh", torch.full((h, w), 1e4)), ("envmap", None)]:
        es = EmitterScene(kind, (h, w), objects={"mirror": mirror}, sensor=sens)
        es.set_emitter(rad, depth)
        imgs[kind] = es.render(spp=32)
    assert psnr(tonemap(imgs["mesh"]), tonemap(imgs["envmap"])) >= 30.0


def test_bridge_gradients_match_finite_differences(mi):
    h, w = 8, 16
    rad = smooth_radiance(h, w)
    depth = wavy_depth(h, w)
    sphere = {"type": "sphere", "center": [0.2, -0.1, -1.2], "radius": 0.35,
              "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.8, 0.8, 0.8]}}}
    es = EmitterScene("mesh", (h, w), objects={"s": sphere},
                      sensor=perspective_sensor(fov_deg=70, width=24, height=24))
    g = torch.Generator().manual_seed(0)
    weight = torch.rand(24, 24, 3, generator=g)

    def loss(r, d):
        return (render_differentiable(es, r, d, spp=1024, seed=3) * weight).sum()

    r = rad.clone().requires_grad_()
    d = depth.clone().requires_grad_()
    loss(r, d).backward()
    # The adjoint pass uses other random numbers than the primal one (Mitsuba requires it), so
    # both sides are estimates; at 1024 spp their noise is well below the tolerance.
    flat = r.grad.abs().reshape(-1)
    for idx in torch.topk(flat, 3).indices.tolist():
        i, j, c = np.unravel_index(idx, (h, w, 3))
        eps = 0.05
        rp, rm = rad.clone(), rad.clone()
        rp[i, j, c] += eps
        rm[i, j, c] -= eps
        fd = (float(loss(rp, depth)) - float(loss(rm, depth))) / (2 * eps)
        assert abs(fd - float(r.grad[i, j, c])) <= 0.05 * abs(fd) + 1e-3, (i, j, c, fd, float(r.grad[i, j, c]))
    # depth pixels seen directly by the camera (interior derivatives of the hit point's uv)
    es_direct = EmitterScene("mesh", (h, w), sensor=perspective_sensor(fov_deg=70, width=24, height=24))

    def loss_direct(dd):
        return (render_differentiable(es_direct, rad, dd, spp=256, seed=5) * weight).sum()

    d2 = depth.clone().requires_grad_()
    loss_direct(d2).backward()
    flat = d2.grad.abs().reshape(-1)
    checked = 0
    for idx in torch.topk(flat, 3).indices.tolist():
        i, j = np.unravel_index(idx, (h, w))
        eps = 1e-3 * float(depth[i, j])
        dp, dm = depth.clone(), depth.clone()
        dp[i, j] += eps
        dm[i, j] -= eps
        fd = (float(loss_direct(dp)) - float(loss_direct(dm))) / (2 * eps)
        assert abs(fd - float(d2.grad[i, j])) <= 0.1 * abs(fd) + 1e-2, (i, j, fd, float(d2.grad[i, j]))
        checked += 1
    assert checked == 3 and float(flat.max()) > 0.1


def test_mitsuba_mesh_holds_the_arrays_it_is_given(mi):
    """A 2 m x 1 m emissive quad built from arrays: its area, normals and texture coordinates are
    the given ones, and a camera looking at it sees its radiance (Mitsuba's own definitions)."""
    from roomlight.core.render.mesh import mitsuba_mesh

    v = np.array([[-1, -0.5, -3], [1, -0.5, -3], [1, 0.5, -3], [-1, 0.5, -3]], np.float64)
    f = np.array([[0, 1, 2], [0, 2, 3]])
    n = np.tile([0.0, 0.0, 1.0], (4, 1))
    uv = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], np.float64)
    emitter = mi.load_dict({"type": "area", "radiance": {"type": "rgb", "value": [2.0, 1.0, 0.5]}})
    black = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.0, 0.0, 0.0]}}
    quad = mitsuba_mesh("quad", v, f, black, normals=n, uvs=uv, emitter=emitter)
    assert float(np.array(quad.surface_area()).ravel()[0]) == pytest.approx(2.0, rel=1e-6)
    params = mi.traverse(quad)
    assert np.allclose(np.array(params["vertex_normals"]).reshape(-1, 3), n)
    assert np.allclose(np.array(params["vertex_texcoords"]).reshape(-1, 2), uv)
    assert np.array_equal(np.array(params["faces"]).reshape(-1, 3), f)
    plain = mitsuba_mesh("plain", v, f, black)  # no normals, no uvs: flat shading, no texture coordinates
    assert not plain.has_vertex_normals() and not plain.has_vertex_texcoords()
    sensor = perspective_sensor((0.0, 0.0, 0.0), (0.0, 0.0, -1.0), (0.0, 1.0, 0.0), 10.0, 8, 8)
    scene = mi.load_dict({"type": "scene", "integrator": {"type": "path", "max_depth": 2}, "sensor": sensor,
                          "quad": quad})
    img = np.array(mi.render(scene, spp=4))[..., :3]
    assert np.allclose(img, [2.0, 1.0, 0.5], atol=1e-4)
