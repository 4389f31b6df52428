"""The command-line interface: outputs, interoperability with Mitsuba's loaders, clean errors."""


import numpy as np
import pytest
from click.testing import CliRunner

from roomlight.cli.main import cli
from roomlight.core.examples import example_room
from roomlight.core.io import read_exr, read_ply, write_exr, write_panorama
from roomlight.core.render.camera import perspective_sensor
from roomlight.core.render.scene import EmitterScene


def run(*args):
    result = CliRunner().invoke(cli, [str(a) for a in args], catch_exceptions=False)
    return result


@pytest.fixture(scope="module")
def pano_file(tmp_path_factory):
    rad, depth = example_room(32)
    path = tmp_path_factory.mktemp("pano") / "room.exr"
    write_panorama(path, (rad.numpy(), depth.numpy()))
    return path


def test_info_reports_variant():
    r = run("info")
    assert r.exit_code == 0, r.output
    assert "mitsuba variant" in r.output and ("llvm_ad_rgb" in r.output or "cuda_ad_rgb" in r.output)


@pytest.mark.mitsuba
def test_emitter_bundle_loads_in_mitsuba_and_matches_in_memory_scene(mi, pano_file, tmp_path):
    out = tmp_path / "bundle"
    r = run("emitter", pano_file, "--out", out)
    assert r.exit_code == 0, r.output
    for name in ("emitter.ply", "radiance.exr", "depth.exr", "scene.xml", "preview.png"):
        assert (out / name).is_file(), name
    scene = mi.load_file(str(out / "scene.xml"))
    ids = [s.id() for s in scene.shapes()]
    assert ids == ["emitter"]
    ply = read_ply(out / "emitter.ply")
    assert ply["vertices"].shape == (32 * 65 + 2 * 64, 3)
    # The scene read back through Mitsuba's PLY and EXR loaders renders like the in-memory one.
    rad, depth = example_room(32)
    r = run("render", out, "--out", tmp_path / "r", "--res", "32x48", "--spp", "64", "--fov", "70",
            "--look-at", "0.3,-0.2,-1", "--sphere", "0.3,-0.4,-1.2,0.25,mirror")
    assert r.exit_code == 0, r.output
    from_file = read_exr(tmp_path / "r" / "render.exr")
    from_file = np.stack([from_file[c] for c in "RGB"], -1)
    es = EmitterScene("mesh", (32, 64), objects={"p": {"type": "sphere", "center": [0.3, -0.4, -1.2], "radius": 0.25,
                                                       "bsdf": {"type": "conductor", "material": "Ag"}}},
                      sensor=perspective_sensor(target=(0.3, -0.2, -1), fov_deg=70, width=48, height=32),
                      integrator={"type": "path", "max_depth": 4})
    es.set_emitter(rad, depth)
    mem = es.render(spp=64).numpy()
    assert (tmp_path / "r" / "render.png").is_file()
    rel = np.abs(from_file - mem).mean() / mem.mean()
    assert rel < 0.02, rel


@pytest.mark.mitsuba
@pytest.mark.parametrize("kind", ["envmap", "sphere:3"])
def test_envmap_and_sphere_bundles(mi, pano_file, tmp_path, kind):
    out = tmp_path / "b"
    r = run("emitter", pano_file, "--as", kind, "--out", out)
    assert r.exit_code == 0, r.output
    scene = mi.load_file(str(out / "scene.xml"))
    if kind == "envmap":
        env = read_exr(out / "envmap.exr")
        assert env["R"].shape == (33, 64)  # pole-to-pole rows for Mitsuba's envmap
        assert len(scene.emitters()) == 1 and not scene.shapes()
    else:
        v = read_ply(out / "emitter.ply")["vertices"][: 32 * 65]  # grid vertices; poles sit at ring centroids
        assert np.allclose(np.linalg.norm(v, axis=1), 3.0, atol=1e-5)


def test_emitter_from_radiance_hdr_and_depth_png(tmp_path):
    from roomlight.core.io import write_depth_png, write_hdr

    rad, depth = example_room(16)
    write_hdr(tmp_path / "r.hdr", rad.numpy())
    write_depth_png(tmp_path / "d.png", depth.numpy())
    r = run("emitter", tmp_path / "r.hdr", "--depth", tmp_path / "d.png", "--out", tmp_path / "o")
    assert r.exit_code == 0, r.output
    v = read_ply(tmp_path / "o" / "emitter.ply")["vertices"][: 16 * 33].reshape(16, 33, 3)[:, :32]
    assert np.allclose(np.linalg.norm(v, axis=-1), depth.numpy(), atol=1.5e-3)  # mm quantisation


def test_user_errors_are_one_line_messages(tmp_path, pano_file):
    r = run("emitter", tmp_path / "missing.exr", "--out", tmp_path / "o")
    assert r.exit_code == 2 and "missing.exr" in r.output and "Traceback" not in r.output
    r = run("emitter", pano_file, "--as", "sphere:-1", "--out", tmp_path / "o")
    assert r.exit_code == 2 and "positive radius" in r.output
    rad, _ = example_room(16)
    write_exr(tmp_path / "rgb.exr", {c: rad[..., i].numpy() for i, c in enumerate("RGB")})
    r = run("emitter", tmp_path / "rgb.exr", "--out", tmp_path / "o")
    assert r.exit_code != 0 and "needs depth" in r.output
    r = run("render", tmp_path / "nowhere", "--out", tmp_path / "o")
    assert r.exit_code == 2 and "no such scene file" in r.output
    r = run("render", tmp_path / "nowhere", "--out", tmp_path / "o", "--sphere", "1,2,3")
    assert r.exit_code == 2 and "radius" in r.output
    r = run("render", tmp_path / "nowhere", "--out", tmp_path / "o", "--origin", "1,2")
    assert r.exit_code == 2 and "three comma-separated numbers" in r.output


def test_negative_radiance_needs_explicit_fix(tmp_path):
    rad, depth = example_room(16)
    rad = rad.clone()
    rad[3, 4, 1] = -0.5
    write_panorama(tmp_path / "neg.exr", (rad.numpy(), depth.numpy()), half=False)
    r = run("emitter", tmp_path / "neg.exr", "--out", tmp_path / "o")
    assert r.exit_code == 2 and "negative" in r.output and "--clamp-negative" in r.output
    r = run("emitter", tmp_path / "neg.exr", "--clamp-negative", "--out", tmp_path / "o")
    assert r.exit_code == 0 and "1 pixel" in r.output


@pytest.mark.slow
@pytest.mark.mitsuba
def test_demo_runs(tmp_path):
    r = run("demo", "--out", tmp_path / "demo", "--height", "16", "--res", "32", "--iterations", "4",
            "--spp", "4", "--gt-spp", "8", "--room", "400201:diffuse", "--room", "400202:mirror")
    assert r.exit_code == 0, r.output
    for name in ("parallax/comparison.png", "parallax/probes_mesh.exr", "parallax/mesh/scene.xml",
                 "report/index.html", "report/report.md", "summary.json", "rooms.md"):
        assert (tmp_path / "demo" / name).is_file(), name
    import json

    summary = json.loads((tmp_path / "demo" / "summary.json").read_text())
    assert summary["methods"][-1] == "direct-envmap" and summary["methods"][0] in ("prior", "direct-al")
    assert summary["materials"] == ["diffuse", "mirror"]
    rows = (tmp_path / "demo" / "rooms.md").read_text().splitlines()
    # header, rule, one row per room in its material, the mean
    assert len(rows) == 5 and "| diffuse |" in rows[2] and "| mirror |" in rows[3] and rows[4].startswith("| **mean**")
    assert "**mean**" in r.output
    bad = run("demo", "--out", tmp_path / "bad", "--room", "400201:velvet")
    assert bad.exit_code == 2 and "SEED:MATERIAL" in bad.output and not (tmp_path / "bad").exists()


@pytest.mark.mitsuba
def test_fit_command_outputs_and_whole_frame_flag(tmp_path):
    import json

    from helpers_scene import make_tiny_scene

    make_tiny_scene(tmp_path / "scene")
    for flag, cropped in (((), True), (("--whole-frame",), False)):
        out = tmp_path / f"fit{len(flag)}"
        r = run("fit", tmp_path / "scene", "--method", "direct-envmap", "--preset", "fast", "--iterations", 2,
                "--spp", 2, "--out", out, "--quiet", *flag)
        assert r.exit_code == 0, r.output
        res = json.loads((out / "result.json").read_text())
        assert res["config"]["crop_to_mask"] is cropped
        # The light's brightness, recomputed from the written panorama with Rec. 709 weights.
        from roomlight.core.io import read_panorama

        rad = read_panorama(out / "panorama.exr").radiance.astype(np.float64)
        lum = rad @ np.array([0.2126, 0.7152, 0.0722])
        assert res["light"]["peak_luminance"] == pytest.approx(lum.max(), rel=1e-5)
        lower_median = np.sort(lum, axis=None)[(lum.size - 1) // 2]  # torch's median of an even count
        assert res["light"]["median_luminance"] == pytest.approx(lower_median, rel=1e-5)
        assert res["light"]["extreme"] is False
        for name in ("panorama.exr", "loss.png", "preview.png", "history.jsonl"):
            assert (out / name).is_file()
