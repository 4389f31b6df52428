"""``roomlight fit-photo`` on the command line: bad inputs stop with one line naming the file and the
problem; a run on a rendered photo writes every output."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from PIL import Image

from roomlight.cli.main import cli


def run(*args):
    args = [str(a) for a in args]
    result = CliRunner().invoke(cli, ["fit-photo", *args], catch_exceptions=False)
    if result.exit_code == 2 and "--out" in args:  # a refused input leaves no output folder behind
        assert not Path(args[args.index("--out") + 1]).exists(), result.output
    return result


@pytest.fixture
def files(tmp_path):
    """A 32 x 24 sRGB photo, a z-depth .npy, an integer mask: every input of the command."""
    rng = np.random.default_rng(0)
    Image.fromarray((rng.random((24, 32, 3)) * 255).astype(np.uint8)).save(tmp_path / "photo.png")
    np.save(tmp_path / "depth.npy", np.full((24, 32), 2.5, np.float32))
    mask = np.zeros((24, 32), np.uint8)
    mask[6:14, 4:12] = 1
    mask[10:20, 18:28] = 2
    Image.fromarray(mask).save(tmp_path / "mask.png")
    return tmp_path


def _one_line_error(result, *needles):
    assert result.exit_code == 2, result.output
    lines = [ln for ln in result.output.splitlines() if ln.strip()]
    errors = [ln for ln in lines if ln.startswith("error: ")]
    assert len(errors) == 1 and "Traceback" not in result.output, result.output
    for needle in needles:
        assert needle in errors[0], (needle, errors[0])
    return errors[0]


def test_mask_of_another_size(files):
    Image.fromarray(np.ones((20, 32), np.uint8)).save(files / "small.png")
    r = run(files / "photo.png", "--depth", files / "depth.npy", "--mask", files / "small.png", "--fov", 60,
            "--out", files / "out")
    _one_line_error(r, "small.png", "32x20", "photo.png", "32x24")


def test_empty_mask(files):
    Image.fromarray(np.zeros((24, 32), np.uint8)).save(files / "empty.png")
    r = run(files / "photo.png", "--depth", files / "depth.npy", "--mask", files / "empty.png", "--fov", 60,
            "--out", files / "out")
    _one_line_error(r, "empty.png", "selects no pixel")


@pytest.mark.parametrize("value, problem", [(np.nan, "NaN or infinite"), (np.inf, "NaN or infinite"),
                                            (0.0, "zero or negative"), (-1.0, "zero or negative")])
def test_bad_depth_values(files, value, problem):
    d = np.full((24, 32), 2.5, np.float32)
    d[3, 4] = value
    np.save(files / "bad.npy", d)
    r = run(files / "photo.png", "--depth", files / "bad.npy", "--mask", files / "mask.png", "--fov", 60,
            "--out", files / "out")
    _one_line_error(r, "bad.npy", problem, "1 of 768 pixels")


def test_depth_of_another_size(files):
    np.save(files / "d2.npy", np.full((12, 16), 2.0, np.float32))
    r = run(files / "photo.png", "--depth", files / "d2.npy", "--mask", files / "mask.png", "--fov", 60,
            "--out", files / "out")
    _one_line_error(r, "d2.npy", "16x12")


def test_unknown_intrinsics(files):
    r = run(files / "photo.png", "--depth", files / "depth.npy", "--mask", files / "mask.png", "--out", files / "out")
    _one_line_error(r, "photo.png", "unknown camera intrinsics", "--fov", "--intrinsics")


def test_bad_intrinsics_text_and_non_square_pixels(files):
    r = run(files / "photo.png", "--depth", files / "depth.npy", "--mask", files / "mask.png", "--intrinsics", "30,30,16",
            "--out", files / "out")
    _one_line_error(r, "fx,fy,cx,cy")
    r = run(files / "photo.png", "--depth", files / "depth.npy", "--mask", files / "mask.png",
            "--intrinsics", "30,40,16,12", "--out", files / "out", "--preset", "fast", "--iterations", 1)
    _one_line_error(r, "photo.png", "square pixels")


def test_no_depth_and_no_estimator(files, monkeypatch):
    import roomlight.fitting.photo.estimator as est

    monkeypatch.setattr(est, "moge_available", lambda: False)
    r = run(files / "photo.png", "--mask", files / "mask.png", "--fov", 60, "--out", files / "out")
    _one_line_error(r, "photo.png", "--depth FILE", "moge")


def test_missing_files_and_unreadable_image(files):
    r = run(files / "nope.png", "--depth", files / "depth.npy", "--mask", files / "mask.png", "--fov", 60,
            "--out", files / "out")
    _one_line_error(r, "nope.png", "does not exist")
    (files / "broken.png").write_bytes(b"not an image")
    r = run(files / "broken.png", "--depth", files / "depth.npy", "--mask", files / "mask.png", "--fov", 60,
            "--out", files / "out")
    _one_line_error(r, "broken.png", "cannot read the image")
    r = run(files / "photo.png", "--depth", files / "depth.npy", "--mask", files / "mask.png", "--fov", 60,
            "--out", files / "out", "--set", "render_size=2")
    _one_line_error(r, "render_size")


def test_photo_case_folder_with_a_bad_camera_json(files):
    case = files / "case"
    case.mkdir()
    (case / "image.png").write_bytes((files / "photo.png").read_bytes())
    (case / "depth.npy").write_bytes((files / "depth.npy").read_bytes())
    (case / "mask.png").write_bytes((files / "mask.png").read_bytes())
    (case / "camera.json").write_text(json.dumps({"format": "roomlight.photo-case", "depth_kind": "planar"}))
    r = run(case, "--out", files / "out")
    _one_line_error(r, "camera.json", "depth_kind")
    (case / "camera.json").write_text(json.dumps({"width": 64, "height": 48, "fov_deg": 60}))
    r = run(case, "--out", files / "out")
    _one_line_error(r, "camera.json", "64x48", "32x24")


@pytest.mark.mitsuba
@pytest.mark.slow
def test_fit_photo_writes_every_output(tmp_path):
    """The command on a rendered photo case: every file of docs/photo.md, readable."""
    from helpers_photo import bright_wall_room, make_tiny_photo
    from roomlight.core.io import read_panorama

    rad, depth = bright_wall_room(16)
    make_tiny_photo(tmp_path / "case", rad, depth, size=(24, 32), spp=32, key=None)
    out = tmp_path / "out"
    r = run(tmp_path / "case", "--out", out, "--iterations", 2, "--spp", 2, "--quiet",
            "--compare", "direct-envmap", "--set", "probe_count=2", "--set", "probe_spp=4",
            "--set", "probe_resolution=16", "--set", "init_samples=2", "--set", "placement_steps=10")
    assert r.exit_code == 0, r.output
    # the default preset, auto, is fast where the renderer runs on a CPU
    from roomlight.core.render.variant import torch_device
    from roomlight.fitting.photo.config import PHOTO_PRESETS

    took = "paper" if torch_device() == "cuda" else "fast"
    assert f"--preset auto: {took}" in r.output
    assert json.loads((out / "result.json").read_text())["settings"]["render_size"] == PHOTO_PRESETS[took].render_size
    for name in ("panorama.exr", "emitter/scene.xml", "emitter/emitter.ply", "materials.json", "render.png", "objects.ply",
                 "render.exr", "compare.png", "loss.png", "history.jsonl", "result.json", "probes.png", "probes.json",
                 "compare/direct-envmap/result.json", "compare/direct-envmap/emitter/envmap.exr"):
        assert (out / name).is_file(), name
    assert not list(out.rglob(".*tmp*")) and not (out / ".fit-state.safetensors").exists()
    res = json.loads((out / "result.json").read_text())
    assert res["method"] == "prior" and res["compared_with"] == ["direct-envmap"]
    assert {"img", "frustum", "frustum_depth", "rep", "total"} <= set(res["objective"])
    assert [m["label"] for m in res["materials"]] == [1, 2]
    assert {"geometry", "initialisation", "fit", "outputs"} <= set(res["timings"])
    assert res["settings"]["iterations"] == 2 and res["camera"]["depth_kind"] == "z"
    pano = read_panorama(out / "panorama.exr")
    assert pano.depth is not None and pano.radiance.shape[:2] == pano.depth.shape
    lum = pano.radiance.astype(np.float64) @ np.array([0.2126, 0.7152, 0.0722])  # Rec. 709
    assert res["light"]["peak_luminance"] == pytest.approx(lum.max(), rel=1e-5)
    probes = json.loads((out / "probes.json").read_text())
    assert len(probes["sites"]) == 2 and probes["rows"] == ["prior", "direct-envmap"]
    assert "prior: best iteration" in r.output and "probes: 2 positions under 2 light(s)" in r.output
    # how far the visible room pins the light's level: the range of the albedos over the range real ones span
    level = res["level_bracket"]
    q_lo, q_hi = level["albedo_quantiles"]
    assert level["points"] > 0 and 0 < q_lo <= q_hi and level["trim"] == 0.1
    assert (level["low"], level["high"]) == pytest.approx((q_hi / 0.9, q_lo / 0.03))
    assert "prior: level: " in r.output
    # ... recomputed from the written files (the panorama, the case, the recorded transform and settings),
    # so a wrong frame, a missing exposure or another set of points shows
    import torch
    from roomlight.fitting.photo import load_photo
    from roomlight.fitting.photo.config import PhotoFitConfig
    from roomlight.fitting.photo.geometry import SceneTransform, build_geometry
    from roomlight.fitting.photo.room_albedo import RoomSurface, apparent_albedo, lifted

    config = PhotoFitConfig(**{k: tuple(v) if isinstance(v, list) else v for k, v in res["settings"].items()})
    f = build_geometry(load_photo(tmp_path / "case"), config).frustum
    t = res["transform"]
    to_room = SceneTransform(np.array(t["rotation"]), t["scale"], np.array(t["translation"]))
    ok = f.normal_ok & (f.radiance.max(-1) < config.tau) & (f.radiance.max(-1) > 0)
    room = RoomSurface(to_room.points(lifted(f.points[ok], f.normals[ok])), to_room.directions(f.normals[ok]),
                       f.radiance[ok])
    a = apparent_albedo(torch.from_numpy(pano.radiance).float(), torch.from_numpy(pano.depth).float(), room).numpy()
    assert level["points"] == len(a)
    assert level["albedo_quantiles"] == pytest.approx(np.quantile(a, [0.1, 0.9]), rel=1e-4)


def test_presets_are_ordered_by_work_and_named_in_help():
    """Each preset is valid; ``balanced`` lies between ``fast`` and ``paper`` in rendering work
    (steps x samples x fitted pixels) and is offered by ``--preset``."""
    from click.testing import CliRunner

    from roomlight.fitting.photo.config import PHOTO_PRESETS

    def work(cfg):
        return cfg.iterations * cfg.spp * cfg.render_size ** 2

    for cfg in PHOTO_PRESETS.values():
        cfg.validate()
    fast, balanced, paper = (PHOTO_PRESETS[k] for k in ("fast", "balanced", "paper"))
    assert work(fast) < work(balanced) < work(paper)
    assert fast.iterations < balanced.iterations < paper.iterations
    help_text = CliRunner().invoke(cli, ["fit-photo", "--help"]).output
    assert "balanced" in help_text and f"{balanced.iterations} it" in help_text


def test_without_a_mask_the_light_is_fitted_to_the_visible_room_and_comes_closer_to_it(tmp_path):
    """No mask: one note, no objects, and the light Mitsuba sees through the photo's pixels (render.exr,
    a ray-traced view of the fitted 2.5D mesh) nearer the photograph after the fit than at its start."""
    from helpers_photo import bright_wall_room, make_tiny_photo

    from roomlight.core.io import read_exr

    rad, depth = bright_wall_room(16)
    make_tiny_photo(tmp_path / "case", rad, depth, size=(48, 64), spp=32, pitch=-10.0)
    (tmp_path / "case" / "mask.png").unlink()
    photo = np.stack([read_exr(tmp_path / "case" / "image.exr")[c] for c in "RGB"], -1)

    def log_error(iterations):
        out = tmp_path / f"fit{iterations}"
        r = run(tmp_path / "case", "--out", out, "--preset", "fast", "--iterations", iterations, "--quiet")
        assert r.exit_code == 0, r.output
        assert sum("no mask" in line for line in r.output.splitlines()) == 1, r.output
        rec = json.loads((out / "result.json").read_text())
        assert rec["objects"] == [] and not (out / "objects.ply").exists() and (out / "probes.png").is_file()
        seen = np.stack([read_exr(out / "render.exr")[c] for c in "RGB"], -1)
        assert seen.shape == photo.shape
        ok = (photo.max(-1) < 0.99) & (photo.mean(-1) > 1e-3)  # unsaturated pixels
        return float(np.median(np.abs(np.log(np.maximum(seen.mean(-1), 1e-6) / photo.mean(-1)))[ok]))

    start, fitted = log_error(1), log_error(60)
    assert fitted < 0.8 * start, (start, fitted)  # measured: 0.31 at the start, 0.13 fitted
    assert fitted < 0.2, fitted
    # and an object goes into that fit like into any other
    r = CliRunner().invoke(cli, ["insert", str(tmp_path / "fit60"), "--object", "sphere", "--at", "32,30",
                                 "--out", str(tmp_path / "ins" / "composite.png")], catch_exceptions=False)
    assert r.exit_code == 0, r.output
    assert json.loads((tmp_path / "ins" / "insert.json").read_text())["objects"], r.output
