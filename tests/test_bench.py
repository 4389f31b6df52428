"""The synthetic benchmark: placement rules, builder, runner, report figures, CLI (scoring: test_bench_scoring.py)."""

import json
import math
from types import SimpleNamespace

import numpy as np
import pytest
import torch

from roomlight.evaluation.harness.errors import BenchError
from roomlight.evaluation.bench.recording import record_ldr
from roomlight.errors import RoomlightError
from roomlight.core.examples import example_room
from roomlight.core.io import write_panorama

#: Small settings shared by the builder fixture and the CLI test (which then resumes the build).
SMALL = {"emitter_height": 16, "width": 32, "height": 32, "spp": 16, "materials": ("diffuse", "mirror")}


# ----------------------------------------------------------------------------------- placement
@pytest.fixture(scope="module")
def room_probe():
    from roomlight.evaluation.bench.placement import EmitterProbe

    _, depth = example_room(32)
    return EmitterProbe(depth)


def _project(p: np.ndarray, fov=65.0, width=128, height=128):
    """Normalised frame coordinates (x right, y down, in [0, 1]) of points for the camera at the
    origin looking along -z with +y up (written out, independent of the placement code)."""
    tx = math.tan(math.radians(fov) / 2)
    ty = tx * height / width
    depth = -p[:, 2]
    assert (depth > 0).all()
    return 0.5 * (p[:, 0] / depth / tx + 1), 0.5 * (1 - p[:, 1] / depth / ty)


def _emitter_distance(probe, dirs):
    """Distance to the emitter mesh by Mitsuba ray casting (for the tests' own check)."""
    mi = probe.escene.mi
    d = dirs / np.linalg.norm(dirs, axis=1, keepdims=True)
    ray = mi.Ray3f(mi.Point3f(0, 0, 0), mi.Vector3f(*[mi.Float(d[:, k].astype(np.float32)) for k in range(3)]))
    return np.array(probe.escene.scene.ray_intersect(ray).t, dtype=np.float64)


def check_placement(probe, placed, cfg):
    """The protocol's rules, checked independently of the placement code."""
    from roomlight.evaluation.bench.placement import STRATA
    from roomlight.fitting.scene.build import object_geometry
    from roomlight.fitting.scene.description import MaterialSpec, ObjectSpec

    assert [o.role for o in placed] == ["input", "input", "probe"] and placed[2].shape == "sphere"
    # Boxes: inside the frame, 0.25-0.35 of the frame width, square in pixels, pairwise disjoint.
    for o in placed:
        b = o.box
        assert 0 <= b.x0 < b.x1 <= 1 and 0 <= b.y0 < b.y1 <= 1
        assert 0.25 <= b.x1 - b.x0 <= 0.35
        assert (b.y1 - b.y0) * cfg.height == pytest.approx((b.x1 - b.x0) * cfg.width)  # square in pixels
    for i in range(3):
        for j in range(i + 1, 3):
            a, b = placed[i].box, placed[j].box
            assert a.x1 <= b.x0 or b.x1 <= a.x0 or a.y1 <= b.y0 or b.y1 <= a.y0
    # Depths: one object per stratum, at that fraction of the depth range [0, t_max].
    assert sorted(o.stratum for o in placed) == sorted(STRATA)
    for o in placed:
        assert o.stratum[0] <= o.fraction <= o.stratum[1]
        assert o.distance == pytest.approx(o.fraction * o.max_distance)
        assert 0 < o.max_distance < o.emitter_distance
    for o in placed:
        spec = o.object_spec(MaterialSpec("diffuse"))
        v, _ = object_geometry(spec)
        # The object projects inside its box, touching it (scaled to fit) unless its size was capped.
        x, y = _project(v, cfg.fov, cfg.width, cfg.height)
        eps = 1e-6
        assert (x >= o.box.x0 - eps).all() and (x <= o.box.x1 + eps).all()
        assert (y >= o.box.y0 - eps).all() and (y <= o.box.y1 + eps).all()
        gap = min(x.min() - o.box.x0, o.box.x1 - x.max(), y.min() - o.box.y0, o.box.y1 - y.max())
        assert gap < 1e-4 or o.relative_radius == pytest.approx(cfg.max_relative_radius)
        # Inside the emitter: every vertex is closer than the emitter mesh in its direction, with margin.
        r = np.linalg.norm(v, axis=1)
        assert (r < (1 - cfg.margin) * _emitter_distance(probe, v) + 1e-6).all()
        # Its bounding sphere: radius = relative radius x distance, centred on the box's centre ray.
        raw, _ = object_geometry(ObjectSpec("raw", shape=spec.shape, mesh=spec.mesh))
        m = spec.matrix()
        centre = m[:3, :3] @ (0.5 * (raw.max(0) + raw.min(0))) + m[:3, 3]  # the object's bbox centre, placed
        assert np.linalg.norm(v - centre, axis=1).max() == pytest.approx(o.radius, rel=1e-4)
        assert np.linalg.norm(centre) == pytest.approx(o.distance, rel=1e-4)


@pytest.mark.mitsuba
@pytest.mark.parametrize("seed", range(4))
def test_placement_rules(room_probe, seed):
    from roomlight.evaluation.bench.placement import PlacementConfig, place_objects

    cfg = PlacementConfig()
    placed = place_objects(room_probe, np.random.default_rng(seed), ["knot", "spiky"], cfg)
    assert [o.id for o in placed] == ["knot", "spiky", "probe"]
    check_placement(room_probe, placed, cfg)


@pytest.mark.mitsuba
def test_placement_of_a_mesh_file(room_probe, tmp_path):
    from roomlight.evaluation.bench.placement import PlacementConfig, place_objects
    from roomlight.core.io import write_ply
    from roomlight.fitting.scene import builtin_shape

    v, f = builtin_shape("cup")
    write_ply(tmp_path / "big cup.ply", v * 3.0 + np.array([5.0, -1.0, 2.0], np.float32), f)  # off-centre, large
    cfg = PlacementConfig(width=160, height=120)
    placed = place_objects(room_probe, np.random.default_rng(5), [str(tmp_path / "big cup.ply"), "cup"], cfg)
    assert placed[0].id == "big cup" and placed[0].mesh.endswith("big cup.ply") and placed[0].shape is None
    assert placed[1].id == "cup"
    check_placement(room_probe, placed, cfg)


@pytest.mark.mitsuba
def test_placement_is_deterministic_and_fails_cleanly(room_probe):
    from roomlight.evaluation.bench.placement import (
        EmitterProbe,
        PlacementConfig,
        PlacementError,
        place_objects,
    )

    a = place_objects(room_probe, np.random.default_rng(3), ["cup", "torus"], PlacementConfig())
    b = place_objects(room_probe, np.random.default_rng(3), ["cup", "torus"], PlacementConfig())
    assert [o.to_dict() for o in a] == [o.to_dict() for o in b]
    tiny = EmitterProbe(torch.full((16, 32), 0.05))
    with pytest.raises(PlacementError, match="from the camera"):
        place_objects(tiny, np.random.default_rng(0), ["knot", "blob"], PlacementConfig())
    with pytest.raises(PlacementError, match="exactly two shapes"):
        place_objects(room_probe, np.random.default_rng(0), ["knot"], PlacementConfig())


# ----------------------------------------------------------------------------------- builder
@pytest.fixture(scope="module")
def panos(tmp_path_factory):
    d = tmp_path_factory.mktemp("panos")
    rad, depth = example_room(32)
    write_panorama(d / "room.exr", (rad.numpy(), depth.numpy()))
    return d


@pytest.fixture(scope="module")
def bench(panos, tmp_path_factory):
    from roomlight.evaluation.bench.builder import BenchConfig, make_benchmark

    out = tmp_path_factory.mktemp("bench")
    manifest = make_benchmark(panos, out, BenchConfig(**SMALL), progress=False)
    return out, manifest


@pytest.mark.mitsuba
def test_builder_writes_scenes_renders_and_masks(bench, panos):
    from PIL import Image

    from roomlight.evaluation.bench.builder import load_emitter_panorama
    from roomlight.evaluation.bench.placement import ScreenBox
    from roomlight.evaluation.bench.rendering import object_coverage
    from roomlight.core.io import luminance, read_exr
    from roomlight.fitting.scene import load_scene

    out, manifest = bench
    assert [s["id"] for s in manifest["scenes"]] == ["room/diffuse", "room/mirror"]
    assert json.loads((out / "manifest.json").read_text())["scenes"] == manifest["scenes"]
    placement = manifest["panoramas"][0]["placement"]
    src_rad, src_depth = load_emitter_panorama(panos / "room.exr", 16)
    for entry in manifest["scenes"]:
        scene = load_scene(out / entry["scene"])
        assert scene.views["input"].objects == ["knot", "spiky"] and scene.views["eval"].objects == ["probe"]
        assert all(o.material.type == entry["material"] for o in scene.objects.values())
        k = scene.metadata["benchmark"]["exposure"]
        assert k == pytest.approx(entry["exposure"])
        pano = scene.emitter.load()
        assert pano.radiance.shape == (16, 32, 3)
        np.testing.assert_allclose(pano.radiance, src_rad.numpy() * k, rtol=1e-5)
        np.testing.assert_allclose(pano.depth, src_depth.numpy(), rtol=1e-6)
        for view in ("input", "eval"):
            v = scene.views[view]
            ch = read_exr(v.image)
            hdr = np.stack([ch[c] for c in "RGB"], -1)
            ldr = np.asarray(Image.open(v.ldr))
            mask = np.asarray(Image.open(v.mask)) > 127
            assert hdr.shape == (32, 32, 3) and ldr.shape == (32, 32, 3) and mask.any()
            np.testing.assert_array_equal(ldr, record_ldr(hdr))
            if view == "input":  # the exposure rule: objects' log-average luminance = 0.18
                y = luminance(hdr[mask].astype(np.float64))
                assert math.exp(np.mean(np.log(y + 1e-6))) == pytest.approx(0.18, rel=1e-4)
            # Each object's pixels (by Mitsuba's primary rays) lie inside its screen box.
            _, ids = object_coverage(scene, view, supersample=2)
            for k_obj, oid in enumerate(v.objects):
                box = ScreenBox(*next(p["box"] for p in placement if p["id"] == oid))
                ii, jj = np.nonzero(ids == k_obj + 1)
                assert ii.size > 0
                assert (jj + 1 >= np.floor(box.x0 * 32)).all() and (jj <= np.ceil(box.x1 * 32)).all()
                assert (ii + 1 >= np.floor(box.y0 * 32)).all() and (ii <= np.ceil(box.y1 * 32)).all()
            assert not (mask & (ids == 0)).any()  # mask pixels are object pixels


@pytest.mark.mitsuba
def test_builder_resumes_and_rejects_bad_inputs(bench, panos, tmp_path):
    from roomlight.evaluation.bench.builder import BenchConfig, make_benchmark

    out, manifest = bench
    stamp = (out / "room" / "mirror" / "scene.json").stat().st_mtime_ns
    again = make_benchmark(panos, out, BenchConfig(**SMALL, n=1), progress=False)  # n is not a scene setting
    assert again["scenes"] == manifest["scenes"] and again["panoramas"] == manifest["panoramas"]
    assert (out / "room" / "mirror" / "scene.json").stat().st_mtime_ns == stamp
    rad, _ = example_room(8)
    (tmp_path / "nodepth").mkdir()
    write_panorama(tmp_path / "nodepth" / "flat.exr", rad.numpy())
    with pytest.raises(BenchError, match=r"flat\.exr: has no depth channel"):
        make_benchmark(tmp_path / "nodepth", tmp_path / "b", BenchConfig(**SMALL), progress=False)
    with pytest.raises(BenchError, match=r"--panos .*empty: holds no \.exr panorama"):
        (tmp_path / "empty").mkdir()
        make_benchmark(tmp_path / "empty", tmp_path / "b", BenchConfig(**SMALL), progress=False)
    with pytest.raises(BenchError, match="--materials: unknown material 'gold'"):
        make_benchmark(panos, tmp_path / "b", BenchConfig(materials=("gold",)), progress=False)
    with pytest.raises(BenchError, match="--shapes: 'teapot' is neither a built-in shape"):
        make_benchmark(panos, tmp_path / "b", BenchConfig(shapes=("knot", "teapot")), progress=False)


# ----------------------------------------------------------------------------------- runner
def _stub_fit(calls):
    """A fitting function returning the true emitter scaled by 2 (or failing for 'broken')."""
    def fit(scene, method, config, out_dir=None, model=None, progress=True):
        calls.append((scene.metadata["benchmark"]["material"], method))
        if method == "broken":
            raise RoomlightError("stub: this method always fails")
        p = scene.emitter.load()
        return SimpleNamespace(radiance=torch.from_numpy(p.radiance) * 2, depth=None, emitter_kind="envmap",
                               history=[{"iteration": 0, "total": 1.0}], best_iteration=0, seconds=0.5)
    return fit


@pytest.fixture(scope="module")
def results(bench, tmp_path_factory):
    from roomlight.evaluation.bench.runner import run_benchmark

    res = tmp_path_factory.mktemp("res")
    calls = []
    summary = run_benchmark(bench[0], res, ["oracle", "x2", "broken"], eval_spp=16, progress=False,
                            fit=_stub_fit(calls))
    return res, summary, calls


@pytest.mark.mitsuba
def test_runner_scores_cases_and_resumes(bench, results):
    from roomlight.evaluation.bench.runner import run_benchmark

    res, summary, calls = results
    assert sorted(summary.done) == ["room/diffuse/oracle", "room/diffuse/x2", "room/mirror/oracle", "room/mirror/x2"]
    assert set(summary.failed) == {"room/diffuse/broken", "room/mirror/broken"}
    assert "stub: this method always fails" in summary.failed["room/mirror/broken"]
    assert sorted(calls) == sorted([(m, s) for m in ("diffuse", "mirror") for s in ("x2", "broken")])
    for mat in ("diffuse", "mirror"):
        case = res / "cases" / "room" / mat
        oracle = json.loads((case / "oracle" / "result.json").read_text())
        x2 = json.loads((case / "x2" / "result.json").read_text())
        assert oracle["emitter_kind"] == "mesh" and x2["emitter_kind"] == "envmap"
        assert x2["iterations"] == 1 and x2["fit_seconds"] == 0.5
        for view in ("input", "eval"):
            assert oracle["metrics"][view]["psnr_ldr"] > x2["metrics"][view]["psnr_ldr"]
            assert oracle["metrics"][view]["rmse_hdr"] < x2["metrics"][view]["rmse_hdr"]
        for f in ("recovered.exr", "input.exr", "eval.exr"):
            assert (case / "x2" / f).is_file()
        assert (case / "broken" / "error.json").is_file() and not (case / "broken" / "result.json").exists()
        # The true emitter encloses every object (the placement's rule); light at infinity records nothing.
        assert oracle["outside"] == {"input": 0.0, "eval": 0.0} and x2["outside"] is None
    # Resume: finished cases are skipped, failed ones retried.
    again = []
    s2 = run_benchmark(bench[0], res, ["oracle", "x2", "broken"], eval_spp=16, progress=False, fit=_stub_fit(again))
    assert len(s2.skipped) == 4 and not s2.done and len(s2.failed) == 2
    assert sorted(again) == [("diffuse", "broken"), ("mirror", "broken")]
    with pytest.raises(BenchError, match="other settings \\(eval_spp: 16 -> 32\\)"):
        run_benchmark(bench[0], res, ["oracle"], eval_spp=32, progress=False, fit=_stub_fit([]))


@pytest.mark.mitsuba
def test_objects_outside_the_recovered_light(bench, tmp_path):
    """The share of each view's object surface a recovered emitter leaves outside, checked against
    the points' own distances for constant-depth emitters, and its place in the report."""
    from roomlight.evaluation.bench.report import outside_cases, write_tables
    from roomlight.evaluation.bench.runner import emitter_depth, objects_outside
    from roomlight.fitting.scene.build import load_scene, scene_points

    out, manifest = bench
    scene = load_scene(out / manifest["scenes"][0]["scene"])
    truth = scene.emitter.load()
    rad = torch.from_numpy(truth.radiance)
    dist = {v: scene_points(scene, scene.view(v).objects, 256, seed=0).double().norm(dim=1).numpy()
            for v in ("input", "eval")}
    far = max(d.max() for d in dist.values())
    near = min(d.min() for d in dist.values())
    mid = float(np.median(dist["eval"]))
    for depth, expect in ((2 * far, 0.0), (0.5 * near, 1.0), (mid, None)):
        got = objects_outside(scene, emitter_depth(SimpleNamespace(radiance=rad, depth=torch.full((16, 32), depth),
                                                                   emitter_kind="mesh")))
        for view in ("input", "eval"):
            want = float((dist[view] > depth).mean()) if expect is None else expect
            assert got[view] == pytest.approx(want, abs=1e-12)  # bilinear lookup of a constant map: exact
    assert 0.3 < objects_outside(scene, torch.full((16, 32), mid))["eval"] < 0.7
    sphere = emitter_depth(SimpleNamespace(radiance=rad, depth=None, emitter_kind=f"sphere:{0.5 * near}"))
    assert sphere.shape == rad.shape[:2] and torch.all(sphere == torch.tensor(0.5 * near, dtype=torch.float32))
    assert objects_outside(scene, sphere) == {"input": 1.0, "eval": 1.0}
    assert emitter_depth(SimpleNamespace(radiance=rad, depth=None, emitter_kind="envmap")) is None
    assert objects_outside(scene, None) is None
    # The report lists the cases with part of the probe outside, worst first.
    metrics = {"psnr_ldr": 20.0, "rmse_hdr": 0.1, "angular_error": 2.0, "pixels": 10}
    records = [{"scene": f"s{i}/diffuse", "panorama": f"s{i}", "material": "diffuse", "method": "prior",
                "emitter_kind": "mesh", "metrics": {"input": metrics, "eval": metrics}, "fit_seconds": 1.0,
                "outside": {"input": 0.0, "eval": share}} for i, share in enumerate((0.0, 0.25, 1.0))]
    assert [o["case"] for o in outside_cases(records)] == ["s2/diffuse/prior", "s1/diffuse/prior"]
    paths = write_tables(records, tmp_path)
    md = paths["markdown"].read_text()
    assert "## Probes outside the recovered light" in md and "| s2/diffuse/prior | 100 % | 20.00 |" in md
    assert "s0/diffuse/prior" not in md.split("## Probes outside")[1]
    assert json.loads(paths["json"].read_text())["outside"]["eval"][1]["share"] == 0.25
    assert paths["cases"].read_text().splitlines()[0].endswith(",outside")


def test_shards_partition_the_cases(bench):
    from roomlight.evaluation.bench.runner import list_cases, parse_shard

    full = list_cases(bench[0], ["a", "b", "c"])
    assert len(full) == 6
    parts = [list_cases(bench[0], ["a", "b", "c"], parse_shard(f"{i}/4")) for i in range(4)]
    assert sorted(str(c) for part in parts for c in part) == sorted(map(str, full))
    assert parse_shard(None) == (0, 1)
    for bad in ("4/4", "x", "1/0", "-1/2"):
        with pytest.raises(BenchError, match="--shard"):
            parse_shard(bad)


@pytest.fixture(scope="module")
def report(results, tmp_path_factory):
    from roomlight.evaluation.bench.report import write_report

    return write_report(results[0], tmp_path_factory.mktemp("rep"), progress=False)


@pytest.mark.mitsuba
def test_report_figures_and_index(report):
    paths = report
    figs = sorted(k for k in paths if k.startswith("figure:"))
    assert figs == ["figure:room/diffuse", "figure:room/mirror"]
    from PIL import Image

    assert Image.open(paths["figure:room/mirror"]).size[0] > 500
    html = paths["html"].read_text()
    assert "figures/room_mirror.png" in html and "<table>" in html
    assert "Failed cases" in paths["markdown"].read_text()
    for text in ("Methods", "Metrics", "Settings", "Fit time", "radial depth", "oracle"):
        assert text in html


@pytest.mark.mitsuba
def test_report_in_a_browser(report, tmp_path):
    """Chromium shows the tables (their 1 px #ccc borders) and the figures (saturated colour)."""
    from helpers_browser import screenshot

    img = screenshot(report["html"], tmp_path / "report.png", size=(1280, 4200), budget_ms=1000).astype(int)
    def longest_run(row):
        d = np.diff(np.r_[0, row.astype(int), 0])
        return (np.flatnonzero(d == -1) - np.flatnonzero(d == 1)).max(initial=0)

    border = np.all(img == 204, axis=-1)
    assert max(longest_run(row) for row in border) > 200, "no table border drawn"
    saturated = (img.max(-1) - img.min(-1)) > 80
    assert saturated.sum() > 20000, "the figures did not load"


# ----------------------------------------------------------------------------------- CLI
@pytest.mark.mitsuba
def test_cli_make_run_report(bench, panos, tmp_path):
    from click.testing import CliRunner

    from roomlight.cli.bench import command

    def run(*args):
        return CliRunner().invoke(command, [str(a) for a in args], catch_exceptions=False)

    r = run("make", "--panos", panos, "--out", bench[0], "--emitter-res", 16, "--res", "32x32", "--spp", 16,
            "--materials", "diffuse,mirror", "--quiet")
    assert r.exit_code == 0, r.output
    assert "1 panoramas x 2 materials = 2 scenes" in r.output
    r = run("run", bench[0], "--out", tmp_path / "res", "--methods", "oracle", "--eval-spp", 8, "--quiet")
    assert r.exit_code == 0, r.output
    assert "2 done, 0 already done, 0 failed" in r.output
    r = run("report", tmp_path / "res", "--no-figures", "--quiet")
    assert r.exit_code == 0, r.output
    assert "| oracle | 2.5D AL |" in r.output
    r = run("run", bench[0], "--out", tmp_path / "res2", "--methods", "prior,direct-al", "--model", tmp_path / "nowhere")
    assert r.exit_code == 2 and "nowhere" in r.output and "Traceback" not in r.output, r.output
    r = run("run", bench[0], "--out", tmp_path / "res2", "--methods", "magic")
    assert r.exit_code == 2 and "error: --methods: unknown method(s) magic" in r.output
    r = run("run", bench[0], "--out", tmp_path / "res2", "--methods", "oracle", "--set", "nonsense=1")
    assert r.exit_code == 2 and "FitConfig.nonsense: unknown field" in r.output


@pytest.mark.mitsuba
def test_masks_do_not_depend_on_ray_batching(bench, monkeypatch):
    from roomlight.evaluation.bench import rendering
    from roomlight.core.render import raycast
    from roomlight.fitting.scene import load_scene

    scene = load_scene(bench[0] / "room" / "diffuse" / "scene.json")
    cov, ids = rendering.object_coverage(scene, "input", supersample=2)
    monkeypatch.setattr(raycast, "MAX_RAYS_PER_CAST", 32 * 2 * 2 * 5)  # five image rows per cast
    cov2, ids2 = rendering.object_coverage(scene, "input", supersample=2)
    np.testing.assert_array_equal(cov, cov2)
    np.testing.assert_array_equal(ids, ids2)


@pytest.mark.mitsuba
def test_render_passes_average_to_one_launch(bench):
    from roomlight.evaluation.bench.rendering import render_passes, view_emitter_scene
    from roomlight.fitting.scene import load_scene

    scene = load_scene(bench[0] / "room" / "diffuse" / "scene.json")
    pano = scene.emitter.load()
    es = view_emitter_scene(scene, "eval", "mesh", pano.radiance.shape[:2])
    es.set_emitter(torch.from_numpy(pano.radiance), torch.from_numpy(pano.depth))
    one = render_passes(es, 8, seed=3)
    np.testing.assert_allclose(one.numpy(), es.render(spp=8, seed=3).numpy(), rtol=1e-6)
    split = render_passes(es, 8, seed=3, max_samples=32 * 32 * 3)  # 3 passes of 3 + 3 + 2 spp
    expect = (es.render(spp=3, seed=3) * 3 + es.render(spp=3, seed=4) * 3 + es.render(spp=2, seed=5) * 2) / 8
    np.testing.assert_allclose(split.numpy(), expect.numpy(), rtol=1e-5, atol=1e-7)


@pytest.mark.mitsuba
def test_builder_with_a_mesh_file_given_by_relative_path(panos, tmp_path, monkeypatch):
    from roomlight.evaluation.bench.builder import BenchConfig, make_benchmark
    from roomlight.core.io import write_ply
    from roomlight.fitting.scene import builtin_shape, load_scene

    monkeypatch.chdir(tmp_path)
    write_ply(tmp_path / "bunny.ply", *builtin_shape("blob"))
    cfg = BenchConfig(emitter_height=16, width=24, height=24, spp=2, materials=("diffuse",), shapes=("bunny.ply", "knot"))
    manifest = make_benchmark(panos, "out", cfg, progress=False)
    scene = load_scene(tmp_path / "out" / manifest["scenes"][0]["scene"])
    assert scene.objects["bunny"].mesh == (tmp_path / "bunny.ply").resolve()
    assert scene.views["input"].objects == ["bunny", "knot"]


def test_cli_paper_flags_reach_the_configs(monkeypatch, tmp_path):
    from click.testing import CliRunner

    import roomlight.evaluation.bench.builder as builder
    import roomlight.evaluation.bench.runner as runner
    from roomlight.cli.bench import command

    seen = {}

    def fake_make(panos, out, cfg, overwrite=False, progress=True):
        seen["make"] = cfg
        return {"panoramas": [], "scenes": []}

    def fake_run(bench, out, methods, cfg, model, eval_spp, shard, progress, scheduler=None, model_name=None):
        seen["run"] = (methods, cfg, eval_spp, shard)
        return runner.RunSummary()

    monkeypatch.setattr(builder, "make_benchmark", fake_make)
    monkeypatch.setattr(runner, "run_benchmark", fake_run)
    r = CliRunner().invoke(command, ["make", "--panos", str(tmp_path), "--out", str(tmp_path / "b"), "--paper",
                                     "--spp", "1024", "--shapes", "cup,torus,blob"])
    assert r.exit_code == 0, r.output
    cfg = seen["make"]
    assert (cfg.emitter_height, cfg.width, cfg.height, cfg.spp) == (512, 1000, 1000, 1024)
    assert cfg.shapes == ("cup", "torus", "blob") and cfg.materials == ("diffuse", "matte", "mirror")
    r = CliRunner().invoke(command, ["run", str(tmp_path), "--out", str(tmp_path / "r"), "--paper", "--methods",
                                     "direct-al,oracle", "--iterations", "7", "--set", "lr=0.05", "--shard", "1/3"])
    assert r.exit_code == 0, r.output
    methods, fit_cfg, spp, shard = seen["run"]
    assert methods == ("direct-al", "oracle") and spp == 4096 and shard == (1, 3)
    assert fit_cfg.iterations == 7 and fit_cfg.lr == 0.05 and fit_cfg.spp == 64
