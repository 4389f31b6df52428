"""The crop benchmark: the protocol's images against closed forms, the baselines' geometry, and the
make -> run -> report round trip."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from click.testing import CliRunner

from roomlight.cli.main import cli
from roomlight.core.geometry.equirect import pixel_directions
from roomlight.evaluation.crops.protocol import (CROP_SIZE, make_crop, perspective_view, render_spheres,
                                                 score_panorama, sphere_mask)

pytestmark = [pytest.mark.usefixtures("one_torch_thread")]


def _direction_panorama(h=64):
    """A panorama whose radiance is its own direction, shifted to be positive: (x + 1, y + 1, z + 1)."""
    return (pixel_directions(h, 2 * h).numpy() + 1.0).astype(np.float32)


def test_the_crop_looks_at_plus_z_level_with_a_60_degree_vertical_field():
    view = perspective_view(_direction_panorama(128), vfov=60.0, size=(192, 256)) - 1.0
    h, w = CROP_SIZE
    centre = view[h // 2 - 1:h // 2 + 1, w // 2 - 1:w // 2 + 1].mean((0, 1))
    np.testing.assert_allclose(centre / np.linalg.norm(centre), [0, 0, 1], atol=0.02)
    # the top row's middle looks 30 degrees up (minus half a pixel), the right column's middle 37.6 left... right
    top = view[0, w // 2 - 1:w // 2 + 1].mean(0)
    assert math.degrees(math.atan2(top[1], top[2])) == pytest.approx(30.0 - 60.0 / 192 / 2, abs=0.6)
    right = view[h // 2 - 1:h // 2 + 1, -1].mean(0)
    half_x = math.degrees(math.atan(math.tan(math.radians(30)) * 256 / 192))
    assert abs(math.degrees(math.atan2(right[0], right[2]))) == pytest.approx(half_x, abs=0.8)


def test_the_crop_maps_the_99th_percentile_to_0_9_through_gamma_2_4():
    # 1.0 everywhere but the lowest rows (2 % of the values) at 16: the 99th percentile of E^(1/2.4) is
    # 16^(1/2.4) = 3.175, so the walls the crop sees map to 0.9 / 3.175 = 0.2835.
    pano = np.ones((100, 200, 3), np.float32)
    pano[-2:] = 16.0
    crop = make_crop(pano)
    np.testing.assert_allclose(crop, 0.9 / 16 ** (1 / 2.4), rtol=1e-5)
    assert crop.shape == (*CROP_SIZE, 3)
    # a few pixels far above the percentile (a lamp straight ahead) are clipped at 1, like a photograph's
    pano[49:51, 99:101] = 1e4
    assert make_crop(pano)[CROP_SIZE[0] // 2, CROP_SIZE[1] // 2].tolist() == [1.0, 1.0, 1.0]


@pytest.mark.mitsuba
def test_spheres_under_a_uniform_light_and_the_mirror_reflects_what_is_behind_the_camera():
    L = np.full((32, 64, 3), 0.5, np.float32)
    s = render_spheres(L, size=48, spp=32)
    m = sphere_mask(48)
    assert m.mean() == pytest.approx(math.pi / 4, abs=0.03)  # the sphere fills the frame
    # reflectance 0.8 (the mask's rim pixels are partly background: 0.2 % over)
    np.testing.assert_allclose(s["mirror"][m].mean(0), 0.8 * 0.5, rtol=5e-3)
    np.testing.assert_allclose(s["mirror"][~m].mean(0), 0.5, rtol=1e-2)        # the background: the light (and rims)
    d = pixel_directions(32, 64).numpy()
    behind = np.repeat(np.where(d[..., 2:] < -0.9, 10.0, 0.1), 3, -1).astype(np.float32)
    mirror = render_spheres(behind, size=48, spp=4)["mirror"]
    assert mirror[22:26, 22:26].mean() == pytest.approx(8.0, rel=0.02)        # the centre sees -z, behind the camera


def test_score_panorama_puts_the_median_at_one_half():
    rng = np.random.default_rng(1)
    pano = rng.lognormal(0, 1, (64, 128, 3)).astype(np.float32)
    out = score_panorama(pano)
    assert out.shape == (128, 256, 3)
    assert np.median(out[out > 0]) == pytest.approx(0.5, rel=0.01)


def test_the_mirrored_crop_puts_the_crop_where_it_was_cut_and_the_constant_its_mean():
    from roomlight.evaluation.crops.predict import crop_to_linear, predict

    # a smooth crop: red grows to the right, green downwards
    yy, xx = np.mgrid[0:CROP_SIZE[0], 0:CROP_SIZE[1]]
    crop = np.stack([xx / (CROP_SIZE[1] - 1), yy / (CROP_SIZE[0] - 1), np.full(xx.shape, 0.5)], -1).astype(np.float32)
    pano = predict("mirrored-crop", crop)
    lin = crop_to_linear(crop)
    h = pano.shape[0]
    # straight ahead (+z, u = 1/2, the equator) is the crop's centre
    np.testing.assert_allclose(pano[h // 2, h], lin[CROP_SIZE[0] // 2, CROP_SIZE[1] // 2], atol=0.02)
    # looking right (-x side of +z: u = 1/2 + a little) shows the crop's right part; behind (-z) the
    # mirrored crop: the two halves meet behind the camera without a seam (both at the crop's middle)
    assert pano[h // 2, h + 8, 0] > pano[h // 2, h, 0] > pano[h // 2, h - 8, 0]
    np.testing.assert_allclose(pano[:, 0], pano[:, -1], atol=0.02)
    np.testing.assert_allclose(pano[h // 2, 0], lin[CROP_SIZE[0] // 2, CROP_SIZE[1] // 2], atol=0.02)
    # up is the crop's top (green 0), down its bottom (green 1)
    assert pano[2, h, 1] < 0.01 and pano[-3, h, 1] > 0.9
    np.testing.assert_allclose(predict("constant-colour", crop)[0, 0], lin.reshape(-1, 3).mean(0), rtol=1e-5)


@pytest.mark.mitsuba
def test_make_run_report_round_trip(tmp_path):
    from roomlight.core.io import write_exr

    rng = np.random.default_rng(3)
    for k in range(2):
        pano = rng.lognormal(0, 0.5, (32, 64, 3)).astype(np.float32)
        write_exr(tmp_path / f"p{k}.exr", {c: pano[..., i] for i, c in enumerate("RGB")}, half=False)
    r = CliRunner().invoke(cli, ["bench", "make-crops", str(tmp_path / "p0.exr"), str(tmp_path / "p1.exr"),
                                 "--out", str(tmp_path / "set"), "--quiet"])
    assert r.exit_code == 0, r.output
    assert (tmp_path / "set" / "p0" / "crop.png").is_file() and (tmp_path / "set" / "p1" / "truth.exr").is_file()
    args = ["bench", "run-crops", str(tmp_path / "set"), "--out", str(tmp_path / "res"), "--spp", "4", "--quiet",
            "--methods", "constant-colour,mirrored-crop"]
    r = CliRunner().invoke(cli, args)
    assert r.exit_code == 0, r.output
    rec = json.loads((tmp_path / "res" / "cases" / "p0" / "mirrored-crop" / "result.json").read_text())
    assert set(rec["scores"]) == {"diffuse", "matte", "mirror"}
    assert set(rec["scores"]["mirror"]) == {"rmse", "si_rmse", "angular_error", "norm_rmse"}
    again = CliRunner().invoke(cli, args)
    assert "0 done, 4 already done" in again.output
    r = CliRunner().invoke(cli, ["bench", "report-crops", str(tmp_path / "res"), "--reference", "mirrored-crop"])
    assert r.exit_code == 0, r.output
    assert "| constant-colour |" in r.output and "LuxDiT" in r.output and "Laval" in r.output
    bad = CliRunner().invoke(cli, ["bench", "run-crops", str(tmp_path / "set"), "--out", str(tmp_path / "x"),
                                   "--methods", "magic"])
    assert bad.exit_code != 0 and "magic" in bad.output and "Traceback" not in bad.output


def test_estimate_rows_turn_the_bundled_prior_s_room_to_face_the_crop_and_refine_moves_it():
    """``estimate`` and ``estimate-refine`` on one crop: a finite panorama at the benchmark's size from the
    bundled prior, and the refined one differs from the plain one (it was fitted to the crop's pixels)."""
    from roomlight.demo import bundled_prior_path
    from roomlight.evaluation.crops.predict import predict
    from roomlight.prior.model.runs import load_run_model

    model = load_run_model(bundled_prior_path(), device="cpu")
    yy, xx = np.mgrid[0:CROP_SIZE[0], 0:CROP_SIZE[1]]
    crop = np.stack([xx / (CROP_SIZE[1] - 1), yy / (CROP_SIZE[0] - 1), np.full(xx.shape, 0.5)], -1).astype(np.float32)
    plain, refined = predict("estimate", crop, model), predict("estimate-refine", crop, model)
    assert plain.shape == refined.shape and plain.shape[1] == 2 * plain.shape[0] and plain.shape[2] == 3
    assert np.isfinite(plain).all() and np.isfinite(refined).all() and plain.min() >= 0
    assert float(np.abs(refined - plain).mean()) > 1e-3 * float(plain.mean())
