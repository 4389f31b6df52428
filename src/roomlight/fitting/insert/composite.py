"""Differential rendering (Debevec 1998): virtual objects composited into the photograph under its
recovered light.

The *local scene* is the photograph's depth mesh in the light's room frame: the fitted objects keep
their fitted materials, every other surface gets a diffuse albedo estimated from the photograph
under the fitted light (:func:`estimate_albedo`). It is rendered twice under the recovered light,
without and with the new objects, with the same sampler and seed, so that every path that never
meets a new object is the same sample in both renders and cancels. Then, in linear radiance:

    composite = photo + (with - without)                    on the local scene
    composite = with                                        on the new objects' own pixels

blended by each pixel's coverage of the new objects (3 x 3 rays per pixel), so their silhouettes
are antialiased. Shadows, contact shadows, reflections of the objects in the scene and of the
scene in the objects all come out of the renderer.

Inserting nothing gives ``with == without`` exactly, so the composite is the photograph.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from roomlight.core.color import luminance_np
from roomlight.errors import RoomlightError
from roomlight.fitting.insert.fitted import FittedPhoto
from roomlight.fitting.insert.objects import InsertSpec, PlacedObject, place_object

__all__ = ["InsertResult", "LocalGeometry", "insert_objects", "place_objects", "composite_objects", "estimate_albedo",
           "seen_texels", "ALBEDO_RANGE", "COVERAGE_RAYS"]

#: The estimated albedo of the scene's surfaces is clamped to this range: below, a surface in shadow
#: of the fitted light would turn black and hide the new objects' light on it; above, a surface the
#: fitted light under-lights would reflect more than it receives.
ALBEDO_RANGE = (0.02, 0.95)
#: Rays per pixel side for the new objects' coverage (3 x 3 per pixel).
COVERAGE_RAYS = 3


@dataclass
class InsertResult:
    """Everything one insertion made (linear RGB images at the output size, (H, W, 3) float32).

    Attributes:
        composite: the photograph with the objects.
        photo: the photograph at the output size.
        with_objects, without_objects: the local scene's renders.
        coverage: (H, W) share of each pixel the new objects cover, in [0, 1].
        shadow: (H, W) luminance ratio with / without on the local scene (1 on the objects).
        albedo: (H, W, 3) the estimated albedo of the local scene's surfaces.
        placed: the objects as placed.
        info: settings and timings (``insert.json``).
    """

    composite: np.ndarray
    photo: np.ndarray
    with_objects: np.ndarray
    without_objects: np.ndarray
    coverage: np.ndarray
    shadow: np.ndarray
    albedo: np.ndarray
    placed: list[PlacedObject]
    info: dict = field(default_factory=dict)


@dataclass
class LocalGeometry:
    """A local scene's shape given instead of the photograph's depth mesh (to measure what the depth mesh's
    shape costs: the photo benchmark gives its rooms' own triangles,
    :func:`roomlight.fitting.insert.view_mesh.mesh_in_view`). Camera frame, metres.

    Attributes:
        vertices: (N, 3) the surfaces other than the photograph's objects; faces: (F, 3) int.
        uv: (N, 2) each vertex's texture coordinate in the photograph (its pixel position over the image
            size, v = 0 on the top row): the estimated albedo, an image, is laid on them through it.
        objects: the photograph's objects by mask label: (vertices (n, 3), faces (f, 3), shading normals
            (n, 3) or None for flat shading), each shaded with its fitted material.
    """

    vertices: np.ndarray
    faces: np.ndarray
    uv: np.ndarray
    objects: dict = field(default_factory=dict)


class _LocalScene:
    """The photograph's depth mesh and fitted objects under the fitted light, in the room frame."""

    def __init__(self, fitted: FittedPhoto, out_hw: tuple[int, int], max_depth: int, with_scene: bool = True,
                 placed=(), enclose: bool = True, geometry: LocalGeometry | None = None):
        from roomlight.fitting.photo.geometry import build_geometry, working_size
        from roomlight.fitting.photo.masks import resize_nearest
        from roomlight.fitting.photo.scene import object_shapes, photo_sensor

        case, cfg, t = fitted.case, fitted.config, fitted.transform
        self.fitted = fitted
        geo = build_geometry(case, cfg)
        gh, gw = working_size(case.height, case.width, cfg.geometry_size)
        labels_g = resize_nearest(case.objects.labels, gh, gw).reshape(-1)
        kept = {o.label for o in geo.objects}
        # The background: triangles of the depth mesh whose three corners belong to no fitted object.
        faces = geo.mesh.faces
        on_object = np.isin(labels_g, list(kept))[faces].any(1)
        self.background_faces = faces[~on_object]
        self.background_vertices = t.points(geo.mesh.vertices)
        ii, jj = np.meshgrid(np.arange(gh), np.arange(gw), indexing="ij")
        # Texture coordinates: v = 0 on the top image row (Mitsuba's convention), pixel centres.
        self.uv = np.stack([(jj.ravel() + 0.5) / gw, (ii.ravel() + 0.5) / gh], 1)
        self.objects = object_shapes(geo.objects, t, fitted.bsdfs()) if geo.objects and with_scene else {}
        object_points = [t.points(o.vertices) for o in geo.objects]
        if geometry is not None:  # another shape in the depth mesh's place (diagnosis)
            self.background_vertices = t.points(np.asarray(geometry.vertices, np.float64))
            self.background_faces = np.asarray(geometry.faces, np.int64)
            self.uv = np.asarray(geometry.uv, np.float64)
            self.objects = self._given_objects(geometry, fitted) if with_scene else {}
            object_points = [t.points(np.asarray(g[0], np.float64)) for g in geometry.objects.values()]
        if not with_scene:  # the light alone: nothing to cast a shadow on or to reflect
            self.background_faces = self.background_faces[:0]
        oh, ow = out_hw
        self.intrinsics = case.intrinsics.scaled(ow, oh)
        self.sensor = photo_sensor(self.intrinsics, t)
        self.max_depth = int(max_depth)
        # The light's surface, pushed out behind the local scene and the new objects where it runs
        # through or in front of them (roomlight.core.emitter.enclose): the photograph's surfaces then
        # receive the light instead of sharing its place.
        self.depth, self.enclosed_share = fitted.depth, 0.0
        if fitted.depth is not None and enclose:
            import torch

            from roomlight.core.emitter.enclose import enclosing_depth

            pts = [self.background_vertices[np.unique(self.background_faces)]]
            pts += object_points if with_scene else []
            pts += [t.points(p.vertices) for p in placed]
            depth, self.enclosed_share = enclosing_depth(np.asarray(fitted.depth), np.concatenate(pts))
            self.depth = torch.from_numpy(depth)

    def _given_objects(self, geometry: LocalGeometry, fitted: FittedPhoto) -> dict:
        """The given objects' meshes in the room frame, each with its fitted material (by label)."""
        from roomlight.core.render.materials import principled_bsdf
        from roomlight.core.render.mesh import mitsuba_mesh
        from roomlight.fitting.photo.scene import object_id

        t, bsdfs, shapes = fitted.transform, fitted.bsdfs(), {}
        for label, (v, f, n) in geometry.objects.items():
            name = object_id(int(label))
            shapes[name] = mitsuba_mesh(name, t.points(np.asarray(v, np.float64)), f,
                                        bsdfs.get(int(label)) or principled_bsdf([0.5] * 3, 0.5, 0.5),
                                        normals=None if n is None else t.directions(np.asarray(n, np.float64)))
        return shapes

    def background(self, albedo: np.ndarray | None):
        """The depth mesh as a Mitsuba mesh, diffuse with ``albedo`` (H, W, 3) as a texture (None: white)."""
        from roomlight.core.render.mesh import mitsuba_mesh
        from roomlight.core.render.variant import mitsuba

        mi = mitsuba()
        if albedo is None:
            refl = {"type": "rgb", "value": [1.0, 1.0, 1.0]}
        else:
            refl = {"type": "bitmap", "data": mi.TensorXf(np.ascontiguousarray(albedo, np.float32)), "raw": True,
                    "filter_type": "bilinear", "wrap_mode": "clamp"}
        return mitsuba_mesh("local_scene", self.background_vertices, self.background_faces,
                            {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": refl}}, uvs=self.uv)

    def render(self, albedo: np.ndarray | None, extra: dict, spp: int, seed: int, radiance=None) -> np.ndarray:
        """The local scene with ``extra`` shapes under the fitted light (or under ``radiance`` (H, W, 3) on
        the light's geometry)."""
        from roomlight.core.render.scene import EmitterScene

        f = self.fitted
        objects = {**self.objects, **extra}
        if len(self.background_faces):
            objects["local_scene"] = self.background(albedo)
        es = EmitterScene(f.kind, tuple(f.radiance.shape[:2]), objects=objects, sensor=self.sensor,
                          integrator={"type": "path", "max_depth": self.max_depth})
        es.set_emitter(f.radiance if radiance is None else radiance, self.depth)
        return es.render(spp=spp, seed=seed).numpy().astype(np.float32)


def seen_texels(fitted: FittedPhoto, intrinsics) -> np.ndarray:
    """(H, W) bool: the light's texels the photograph shows.

    A texel is seen when its point on the light (its direction times its depth in the room frame; for a
    light at infinity, its direction from the camera) projects inside the photograph's frame in front of
    the camera. Occlusion by the photographed scene is not tested: a texel behind a fitted object but
    within the frame counts as seen, since the object's own pixels constrained the light around it.
    """
    import torch

    from roomlight.core.geometry.equirect import pixel_directions

    h, w = fitted.radiance.shape[:2]
    dirs = pixel_directions(h, w, dtype=torch.float64).numpy()
    t = fitted.transform
    if fitted.depth is not None:
        v = dirs * np.asarray(fitted.depth, np.float64)[..., None] - t.translation
    else:
        v = dirs
    cam = v @ t.rotation  # room -> camera frame (the rotation is orthonormal; the scale does not move a ray)
    z = -cam[..., 2]
    front = z > 1e-9
    zs = np.where(front, z, 1.0)
    x = intrinsics.cx + intrinsics.fx * cam[..., 0] / zs
    y = intrinsics.cy - intrinsics.fy * cam[..., 1] / zs
    return front & (x >= 0) & (x <= intrinsics.width) & (y >= 0) & (y <= intrinsics.height)


def _unseen_shares(local: _LocalScene, fitted: FittedPhoto, placed, albedo, extra, with_obj, spp: int,
                   seed: int) -> list[float | None]:
    """Per object, the share of its pixels' luminance that the light's unseen texels give: the objects
    rendered under the light with its seen texels dark, over the same under the whole light (same seed)."""
    import torch

    seen = torch.from_numpy(seen_texels(fitted, local.intrinsics))
    unseen_light = fitted.radiance * (~seen)[..., None].to(fitted.radiance.dtype)
    unseen = local.render(albedo, extra, spp, seed, radiance=unseen_light)
    whole_y, unseen_y = luminance_np(with_obj), luminance_np(unseen)  # (H, W), once for every object
    shares = []
    for p in placed:
        own = _coverage(local, [p]) > 0.5
        total = float(whole_y[own].sum())
        shares.append(None if not own.any() or total <= 0 else round(float(unseen_y[own].sum()) / total, 4))
    return shares


def estimate_albedo(photo: np.ndarray, white: np.ndarray, lo: float = ALBEDO_RANGE[0],
                    hi: float = ALBEDO_RANGE[1]) -> np.ndarray:
    """Diffuse albedo of the local scene: the photograph over the render of the same scene with white
    surfaces (what an albedo of 1 would look like under the fitted light), clamped to [lo, hi].

    Args:
        photo, white: (H, W, 3) linear radiance at the same size.
    Returns:
        (H, W, 3) float32 albedo; pixels the white render leaves dark get the middle of the range.
    """
    lit = white > 1e-4
    a = np.where(lit, photo / np.maximum(white, 1e-4), 0.5 * (lo + hi))
    return np.clip(a, lo, hi).astype(np.float32)


def _coverage(local: _LocalScene, placed: list[PlacedObject], n: int = COVERAGE_RAYS) -> np.ndarray:
    """(H, W) share of each pixel's n x n rays whose first hit is a new object."""
    from roomlight.core.render.mesh import mitsuba_mesh
    from roomlight.core.render.variant import mitsuba

    mi = mitsuba()
    t = local.fitted.transform
    k = local.intrinsics
    h, w = k.height, k.width
    black = {"type": "diffuse"}
    new = {f"new_{i}": mitsuba_mesh(f"new_{i}", t.points(p.vertices), p.faces, black) for i, p in enumerate(placed)}
    rest = dict(local.objects)
    if len(local.background_faces):
        rest["local_scene"] = local.background(None)

    def scene_of(shapes: dict):
        return mi.load_dict({"type": "scene", **shapes}) if shapes else None

    s_new, s_rest = scene_of(new), scene_of(rest)
    offsets = (np.arange(n) + 0.5) / n
    hits = np.zeros((h, w), np.float64)
    jj, ii = np.meshgrid(np.arange(w), np.arange(h))
    for oy in offsets:
        for ox in offsets:
            d = np.stack([(jj + ox - k.cx) / k.fx, -(ii + oy - k.cy) / k.fy, -np.ones((h, w))], -1).reshape(-1, 3)
            d = t.directions(d / np.linalg.norm(d, axis=1, keepdims=True))
            o = np.broadcast_to(t.translation, d.shape)
            ray = mi.Ray3f(mi.Point3f(*[mi.Float(o[:, c].astype(np.float32)) for c in range(3)]),
                           mi.Vector3f(*[mi.Float(d[:, c].astype(np.float32)) for c in range(3)]))
            t_new = np.array(s_new.ray_intersect(ray).t) if s_new is not None else np.full(len(d), np.inf)
            t_rest = np.array(s_rest.ray_intersect(ray).t) if s_rest is not None else np.full(len(d), np.inf)
            hits += ((t_new < t_rest) & np.isfinite(t_new)).reshape(h, w)
    return (hits / (n * n)).astype(np.float32)


def place_objects(fitted: FittedPhoto, specs: list[InsertSpec]) -> list[PlacedObject]:
    """Each of ``specs`` placed on the fitted photograph's surfaces (camera frame)."""
    from roomlight.fitting.photo.unproject import unproject

    case = fitted.case
    valid = np.isfinite(case.depth) & (case.depth > 0)
    points = unproject(np.where(valid, case.depth, 1.0), case.intrinsics, case.depth_kind)
    points[~valid] = np.nan
    up = fitted.transform.rotation.T @ np.array([0.0, 1.0, 0.0])  # the room's up in the camera frame
    return [place_object(s, points, up, where=f"object {k} ({s.object})") for k, s in enumerate(specs)]


def insert_objects(fitted: FittedPhoto, specs: list[InsertSpec], size: int = 512, spp: int = 256, seed: int = 0,
                   max_depth: int = 5, say=None, unseen_share: bool = True) -> InsertResult:
    """Composite ``specs`` into the fitted photograph (module docstring).

    Args:
        fitted: a ``fit-photo`` output (:func:`~roomlight.fitting.insert.fitted.load_fitted_photo`).
        specs: the objects; an empty list gives back the photograph.
        size: longest side of the output in pixels (never larger than the photograph).
        spp: samples per pixel of the two renders (and of the white render for the albedo).
        seed: the renders' seed (the same for both: the difference is then the objects' effect).
        max_depth: longest light path.
        say: called with one line per step, or None.
        unseen_share: record each object's share of shading from the light's unseen parts (see
            :func:`composite_objects`; one more render).
    """
    t0 = time.perf_counter()
    placed = place_objects(fitted, specs)
    t_place = time.perf_counter() - t0
    result = composite_objects(fitted, placed, size, spp, seed, max_depth, say, unseen_share=unseen_share)
    result.info["timings_s"]["place"] = round(t_place, 3)
    result.info["timings_s"]["total"] = round(time.perf_counter() - t0, 3)
    return result


def composite_objects(fitted: FittedPhoto, placed: list[PlacedObject], size: int = 512, spp: int = 256,
                      seed: int = 0, max_depth: int = 5, say=None, local_scene: bool = True,
                      unseen_share: bool = False, enclose: bool = True, albedo: np.ndarray | None = None,
                      geometry: LocalGeometry | None = None) -> InsertResult:
    """Composite objects already placed (camera frame) into the fitted photograph.

    ``local_scene=False`` renders the objects under the light alone, without the photograph's depth mesh
    and fitted objects: no shadow and nothing of the scene in their reflections (a naive paste, the
    baseline differential rendering improves on). ``unseen_share``: also render the objects under the
    light's texels the photograph does not show (:func:`seen_texels`) and record, per object, the share of
    its shading they give (``unseen_light_share`` in ``info["objects"]``): how much of its look rests on the
    prior's guess of the room rather than on what the photograph showed. ``enclose=False`` keeps a 2.5D
    light's surface where it is, even through the local scene (:mod:`roomlight.core.emitter.enclose`:
    for comparison only). ``albedo``: (h, w, 3) the local scene's albedo at the working size, used instead of
    the one estimated from the photograph (to measure what that estimate costs: the scene's true albedo).
    ``geometry``: the local scene's shape instead of the photograph's depth mesh (:class:`LocalGeometry`; to
    measure what the depth mesh's shape costs: the scene's true triangles).
    """
    from roomlight.fitting.photo.geometry import resize_image, working_size

    say = say or (lambda _m: None)
    t0 = time.perf_counter()
    case = fitted.case
    oh, ow = working_size(case.height, case.width, size)
    timings = {}

    t1 = time.perf_counter()
    local = _LocalScene(fitted, (oh, ow), max_depth, with_scene=local_scene, placed=placed, enclose=enclose,
                        geometry=geometry)
    photo = resize_image(case.image, oh, ow)
    if albedo is not None:
        albedo = np.asarray(albedo, np.float32)
        if albedo.shape != photo.shape:
            raise RoomlightError(f"composite_objects: albedo is {albedo.shape}, the working size {photo.shape}")
    elif local_scene:
        say(f"estimating the scene's albedo under the {fitted.method} light ({ow}x{oh}, {spp} spp)")
        white = local.render(None, {}, spp, seed + 1)
        albedo = estimate_albedo(photo, white)
    else:
        albedo = np.full_like(photo, 0.5 * sum(ALBEDO_RANGE))
    timings["albedo"] = time.perf_counter() - t1

    t2 = time.perf_counter()
    tr = fitted.transform
    extra = {}
    from roomlight.core.render.mesh import mitsuba_mesh

    for k, p in enumerate(placed):
        extra[f"new_{k}"] = mitsuba_mesh(f"new_{k}", tr.points(p.vertices), p.faces, p.bsdf)
    say(f"rendering the local scene without and with {len(placed)} object(s)")
    without = local.render(albedo, {}, spp, seed)
    with_obj = local.render(albedo, extra, spp, seed) if placed else without.copy()
    timings["render"] = time.perf_counter() - t2

    t3 = time.perf_counter()
    cov = _coverage(local, placed) if placed else np.zeros((oh, ow), np.float32)
    a = cov[..., None]
    composite = np.maximum(a * with_obj + (1.0 - a) * (photo + (with_obj - without)), 0.0).astype(np.float32)
    eps = 1e-4
    shadow = (luminance_np(with_obj) + eps) / (luminance_np(without) + eps)
    shadow = np.where(cov > 0, 1.0, shadow).astype(np.float32)
    timings["composite"] = time.perf_counter() - t3
    timings["total"] = time.perf_counter() - t0
    objects_info = [p.to_dict() for p in placed]
    if unseen_share and placed:
        t4 = time.perf_counter()
        say("rendering the objects under the light's parts the photograph does not show")
        for entry, share in zip(objects_info, _unseen_shares(local, fitted, placed, albedo, extra, with_obj, spp,
                                                                 seed)):
            entry["unseen_light_share"] = share
        timings["unseen_share"] = time.perf_counter() - t4
    info = {"light": fitted.method, "light_kind": fitted.kind, "local_scene": local_scene, "fit": str(fitted.folder),
            "exposure_ev": float(fitted.exposure_ev), "size": [oh, ow],
            "spp": spp, "seed": seed, "max_depth": max_depth, "albedo_range": list(ALBEDO_RANGE),
            "light_enclosing_scene": {"on": bool(enclose and fitted.depth is not None),
                                      "texels_moved": round(local.enclosed_share, 4)},
            "coverage_rays": COVERAGE_RAYS ** 2, "objects": objects_info,
            "timings_s": {k: round(v, 3) for k, v in timings.items()}}
    return InsertResult(composite, photo, with_obj, without, cov, shadow, albedo, placed, info)
