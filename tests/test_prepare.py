"""roomlight prepare: the exact inverse tone mapping, nadir detection and inpainting, the 12-view
depth fusion with the synthetic estimator, the adapters' errors, and the command end to end
(bad inputs named, nothing half-written, resumable, accepted by ``roomlight train``)."""

from __future__ import annotations

import json
import math
import sys
import types

import numpy as np
import pytest
import torch
from click.testing import CliRunner

from roomlight.core.color import luminance_np
from roomlight.prior.data.toy import toy_panorama
from roomlight.errors import RoomlightError
from roomlight.datagen.prepare import (DisplayMap, SyntheticEstimator, detect_nadir_cap, estimate_panorama_depth,
                               inpaint_nadir, resolve_inpainter)
from roomlight.datagen.prepare.fusion import floor_distance

pytestmark = pytest.mark.usefixtures("one_torch_thread")


def _room(seed: int, height: int = 64):
    rad, depth = toy_panorama(seed, height)
    return rad.numpy().astype(np.float32), depth.numpy().astype(np.float64)


def _cap(rad: np.ndarray, deg: float) -> np.ndarray:
    """Black out the rows whose centre lies within ``deg`` of the nadir (as ``roomlight synth --nadir-cap`` does)."""
    h = rad.shape[0]
    out = rad.copy()
    out[(np.arange(h) + 0.5) / h * 180.0 > 180.0 - deg] = 0.0
    return out


def _theta(h: int) -> np.ndarray:
    return (np.arange(h) + 0.5) * math.pi / h


# --------------------------------------------------------------------------------------------
# Tone mapping


def test_display_map_inverts_to_float_precision_and_matches_the_formula(rng):
    # 14 decades of radiance, saturated colours, black pixels
    rad = 10.0 ** rng.uniform(-6, 8, (32, 64, 1)) * rng.uniform(0, 1, (32, 64, 3))
    rad[0, :4] = 0.0
    m = DisplayMap.fit(rad)
    d = m.forward(rad)
    back = m.inverse(d)
    rel = (np.abs(back - rad) / np.maximum(rad, 1e-300)).max(axis=-1)
    # "float precision" is what the curve's conditioning allows: near white the curve is nearly
    # flat, and a rounding of L_d by eps moves L by kappa eps, kappa = 1 / (d ln L_d / d ln L)
    L = luminance_np(rad) * m.exposure
    slope = 1 + (L / m.white**2) / (1 + L / m.white**2) - L / (1 + L)
    kappa = 1 / np.maximum(slope, 1e-300)
    eps = np.finfo(np.float64).eps
    pos = L > 0
    assert (rel[pos] <= 16 * eps * np.maximum(kappa[pos], 1)).all()
    assert float(rel[pos & (kappa < 10)].max()) < 1e-14 and np.array_equal(back[0, :4], rad[0, :4])
    # float32 data through a float32 display image: float32 rounding, amplified the same way
    r32 = rad.astype(np.float32)
    back32 = m.inverse(m.forward(r32).astype(np.float32)).astype(np.float32)
    rel32 = (np.abs(back32 - r32) / np.maximum(r32, 1e-30)).max(axis=-1)
    ok = (r32 > 1e-30).all(axis=-1)
    assert (rel32[ok] <= 16 * np.finfo(np.float32).eps * np.maximum(kappa[ok], 1)).all()
    # the forward map, pixel by pixel from the paper's formula
    i, j = 5, 7
    x = rad[i, j] * m.exposure
    L = 0.2126 * x[0] + 0.7152 * x[1] + 0.0722 * x[2]
    Ld = L * (1 + L / m.white**2) / (1 + L)
    np.testing.assert_allclose(d[i, j], (x * Ld / L) ** (1 / 2.2), rtol=1e-12)
    # white is the brightest pixel: it maps to display luminance exactly 1
    y = luminance_np(d ** 2.2)
    assert abs(float(y.max()) - 1.0) < 1e-12
    # the simple operator's inverse L_d / (1 - L_d) is not this operator's inverse: it overshoots
    # (it ignores the white point: a third too bright at half the white, unbounded at the white)
    grey = np.array([[[0.5, 0.5, 0.5], [0.9, 0.9, 0.9], [1.0, 1.0, 1.0]]]) * 1000.0
    g = DisplayMap(exposure=1.0, white=1000.0)
    ld = luminance_np(g.forward(grey) ** 2.2)[0]
    naive = ld / np.maximum(1 - ld, 1e-300) / 1000.0
    assert naive[0] > 1.3 * 0.5 and naive[1] > 2 * 0.9 and naive[2] > 1e6
    np.testing.assert_allclose(g.inverse(g.forward(grey)), grey, rtol=1e-9)


# --------------------------------------------------------------------------------------------
# Nadir


@pytest.mark.parametrize("deg", [10.0, 20.0, 33.0])
def test_detect_nadir_cap_finds_the_black_rows(deg):
    rad, _ = _room(3, 64)
    capped = _cap(rad, deg)
    rows = int(((np.arange(64) + 0.5) / 64 * 180 > 180 - deg).sum())
    assert detect_nadir_cap(capped) == pytest.approx(rows * 180 / 64)
    assert detect_nadir_cap(rad) == 0.0
    # a dark but real floor is not a blind spot
    dim = rad.copy()
    dim[-10:] *= 0.01
    assert detect_nadir_cap(dim) == 0.0


def test_detect_nadir_cap_covers_an_off_centre_blind_spot():
    rad, _ = _room(4, 64)
    h, w = 64, 128
    th = _theta(h)[:, None]
    phi = (np.arange(w) + 0.5) / w * 2 * math.pi
    # a disc of 18 deg around a point 4 deg from the nadir: its rim is ragged in the grid
    c = np.array([math.sin(math.radians(176)), math.cos(math.radians(176)), 0.0])
    d = np.stack([np.sin(phi)[None] * np.sin(th), np.cos(th) * np.ones_like(phi)[None],
                  -np.cos(phi)[None] * np.sin(th)], axis=-1)
    blind = np.degrees(np.arccos(np.clip(d @ c, -1, 1))) < 18
    rad[blind] = 0
    cap = detect_nadir_cap(rad)
    reach = 180 - np.degrees(th[:, 0])[blind.any(axis=1)].min()
    assert reach <= cap <= reach + 180 / 64 * 2


def test_inpainted_cap_keeps_the_rest_bit_identical_and_joins_its_border():
    inpainter = resolve_inpainter("telea")
    for seed in range(6):
        rad, _ = _room(seed, 64)
        capped = _cap(rad, 20.0)
        res = inpaint_nadir(capped, detect_nadir_cap(capped), inpainter)
        h = 64
        i0 = h - res.rows
        assert res.rows == 7
        assert np.array_equal(res.radiance[:i0], capped[:i0])  # bit for bit
        y = luminance_np(res.radiance)
        assert np.isfinite(res.radiance).all() and y[i0:].min() > 0.3 * y[i0 - 1].min()  # no black hole
        ly = np.log(y)
        step = np.abs(ly[i0] - ly[i0 - 1]).mean()          # across the seam
        above = np.abs(ly[i0 - 1] - ly[i0 - 2]).mean()     # the local gradient above it
        truth_step = np.abs(np.log(luminance_np(rad[i0])) - np.log(luminance_np(rad[i0 - 1]))).mean()
        assert step <= max(above, truth_step), (seed, step, above, truth_step)
        # the cap's brightness is the floor's: within 25 % of the truth's mean
        assert 0.75 < y[i0:].mean() / luminance_np(rad[i0:]).mean() < 1.25


def test_inpaint_nadir_refuses_a_cap_above_the_horizon_and_a_misbehaving_inpainter():
    rad, _ = _room(1, 32)
    with pytest.raises(RoomlightError, match="below the horizon"):
        inpaint_nadir(rad, 100.0, resolve_inpainter("ns"))
    with pytest.raises(RoomlightError, match="shape"):
        inpaint_nadir(rad, 20.0, lambda img, mask: img[:-1])
    with pytest.raises(RoomlightError, match="NaN"):
        inpaint_nadir(rad, 20.0, lambda img, mask: np.full_like(img, np.nan))


def test_opencv_inpainters_fill_a_smooth_ramp():
    yy, xx = np.mgrid[0:64, 0:64] / 64.0
    img = np.stack([0.2 + 0.3 * xx, 0.1 + 0.2 * yy, 0.3 + 0.1 * xx * yy], -1).astype(np.float32)
    mask = np.zeros((64, 64), bool)
    mask[20:44, 20:44] = True
    for name in ("telea", "ns"):
        out = resolve_inpainter(name)(np.where(mask[..., None], 0, img), mask)
        assert np.abs(out[mask] - img[mask]).mean() < 0.03, name


def test_lama_adapter_explains_what_is_missing(monkeypatch, tmp_path):
    monkeypatch.setitem(sys.modules, "simple_lama_inpainting", None)
    with pytest.raises(RoomlightError, match="simple-lama-inpainting"):
        resolve_inpainter("lama")
    calls = {}

    class FakeLama:  # stands in for the package: pads to a multiple of 8 as the real one does
        def __init__(self, device):
            import os

            calls["weights"] = os.environ["LAMA_MODEL"]

        def __call__(self, image, mask):
            from PIL import Image

            a = np.asarray(image)
            pad = np.zeros((-(-a.shape[0] // 8) * 8, -(-a.shape[1] // 8) * 8, 3), np.uint8)
            pad[:a.shape[0], :a.shape[1]] = a
            pad[:a.shape[0], :a.shape[1]][np.asarray(mask) > 0] = 128
            return Image.fromarray(pad)

    monkeypatch.setitem(sys.modules, "simple_lama_inpainting", types.SimpleNamespace(SimpleLama=FakeLama))
    monkeypatch.delenv("LAMA_MODEL", raising=False)
    with pytest.raises(RoomlightError, match="LAMA_MODEL"):
        resolve_inpainter("lama")
    with pytest.raises(RoomlightError, match="does not exist"):
        resolve_inpainter(f"lama:{tmp_path / 'nope.pt'}")
    weights = tmp_path / "big-lama.pt"
    weights.write_bytes(b"x")
    lama = resolve_inpainter(f"lama:{weights}")
    assert calls["weights"] == str(weights)
    mask = np.zeros((30, 30), bool)
    mask[10:20, 10:20] = True
    out = lama(np.full((30, 30, 3), 0.25, np.float32), mask)
    assert out.shape == (30, 30, 3)
    assert abs(float(out[15, 15, 0]) - 128 / 255) < 1e-6 and abs(float(out[0, 0, 0]) - 64 / 255) < 1e-6


def test_moge_adapter_and_unknown_names_explain_what_is_missing(monkeypatch, tmp_path):
    from roomlight.datagen.prepare import resolve_estimator

    monkeypatch.setitem(sys.modules, "moge", None)
    with pytest.raises(RoomlightError, match="MoGe package"):
        resolve_estimator("moge").make()
    monkeypatch.setitem(sys.modules, "moge", types.ModuleType("moge"))
    monkeypatch.delenv("ROOMLIGHT_MOGE_WEIGHTS", raising=False)
    with pytest.raises(RoomlightError, match="ROOMLIGHT_MOGE_WEIGHTS"):
        resolve_estimator("moge").make()
    with pytest.raises(RoomlightError, match="does not exist"):
        resolve_estimator(f"moge:{tmp_path / 'model.pt'}").make()
    with pytest.raises(RoomlightError, match="unknown depth estimator"):
        resolve_estimator("midas")
    with pytest.raises(RoomlightError, match="kind must be one of"):
        resolve_estimator("synthetic:inverse")
    with pytest.raises(RoomlightError, match="cannot import"):
        resolve_estimator("no_such_module_xyz:estimate")
    with pytest.raises(RoomlightError, match="unknown inpainter"):
        resolve_inpainter("photoshop")


# --------------------------------------------------------------------------------------------
# Depth


def _camera_height(depth: np.ndarray) -> float:
    """A toy room's floor is the plane y = -h: the bottom row sees it at r |cos(theta)| = h."""
    h = depth.shape[0]
    return float(np.median(depth[-1] * -math.cos(_theta(h)[-1])))


def _continuity(d: np.ndarray, truth: np.ndarray) -> tuple[float, float, float]:
    """Seam error, interior column-pair error (same statistic), pole-row spread (relative)."""
    lf, lt = np.log(d), np.log(truth)
    seam = np.abs((lf[:, 0] - lf[:, -1]) - (lt[:, 0] - lt[:, -1])).mean()
    inner = np.mean([np.abs((lf[:, j + 1] - lf[:, j]) - (lt[:, j + 1] - lt[:, j])).mean() for j in range(d.shape[1] - 1)])
    pole = max(float(np.ptp(lf[0]) - np.ptp(lt[0])), float(np.ptp(lf[-1]) - np.ptp(lt[-1])))
    return float(seam), float(inner), pole


def test_floor_distance_of_the_true_depth_is_the_camera_height():
    for seed in range(4):
        _, depth = _room(seed, 64)
        assert floor_distance(depth) == pytest.approx(_camera_height(depth), rel=2e-3)


@pytest.mark.parametrize("kind", ["affine", "scale", "metric"])
def test_fused_depth_of_procedural_rooms(kind):
    results = []
    for seed in range(4):
        rad, truth = _room(seed, 64)
        est = SyntheticEstimator(truth, kind=kind, seed=seed)
        res = estimate_panorama_depth(rad, est, camera_height=_camera_height(truth))
        d = res.depth.astype(np.float64)
        absrel = float(np.mean(np.abs(d - truth) / truth))
        seam, inner, pole = _continuity(d, truth)
        results.append(absrel)
        assert absrel <= 0.03, (kind, seed, absrel)
        assert seam <= 2 * inner + 1e-3, (kind, seed, seam, inner)   # the seam column is like any other
        assert pole <= 0.03, (kind, seed, pole)   # each pole row is one point (up to the 1 % pixel noise)
        assert res.fusion.overlap_after < 0.02 and res.fusion.filled == 0
        if kind != "affine":
            # the solve found each view's scale: fused / true is one constant (prediction = z / s),
            # to within the views' own bias fields (+-2 %), which no per-view scale can remove.
            # (An affine view's s and t trade against each other over its small depth range, so
            # only their combination, tested through AbsRel, is well determined.)
            true_s = np.array([est.distortion(k)[0] for k in range(12)])
            ratio = np.log(np.array(res.fusion.scales) / true_s)
            assert float(np.std(ratio)) < est.bias, (kind, seed, np.std(ratio))
        if kind != "metric":
            assert res.fusion.overlap_before > 0.1  # the views disagreed before the alignment
        else:
            assert res.scale == 1.0
    print(kind, "AbsRel per room:", [round(a, 4) for a in results])


def test_no_seam_or_pole_step_without_pixel_noise():
    # per-view scales, shifts and bias fields, but no pixel noise: any step left is the fusion's
    for seed in range(3):
        rad, truth = _room(seed + 10, 64)
        est = SyntheticEstimator(truth, kind="affine", seed=seed, noise=0.0)
        d = estimate_panorama_depth(rad, est, camera_height=_camera_height(truth)).depth.astype(np.float64)
        seam, inner, pole = _continuity(d, truth)
        assert pole < 0.005 and seam <= 1.5 * inner + 1e-4, (seed, pole, seam, inner)


def test_non_metric_depth_puts_the_floor_at_the_camera_height():
    rad, truth = _room(7, 64)
    res = estimate_panorama_depth(rad, SyntheticEstimator(truth, kind="scale", seed=2), camera_height=1.6)
    assert res.floor_m == pytest.approx(1.6, rel=1e-6)
    assert floor_distance(res.depth) == pytest.approx(1.6, rel=1e-3)
    # the same room at its true height: metres
    ratio = res.depth / truth
    assert float(np.median(ratio)) == pytest.approx(1.6 / _camera_height(truth), rel=0.02)


def test_a_callable_estimator_with_invalid_pixels_is_fused_and_filled():
    rad, truth = _room(2, 32)
    syn = SyntheticEstimator(truth, kind="metric", seed=0, bias=0.0, noise=0.0, metric_jitter=0.0)

    def est(view):  # distance along the ray, and "sky" (invalid) in the upper part of view 0
        d = syn.true_distance(view)
        valid = np.ones_like(d, bool)
        if view.index == 0:
            valid[: d.shape[0] // 2] = False
        return d, valid

    est.kind, est.depth_type = "metric", "distance"
    res = estimate_panorama_depth(rad, est)
    assert float(np.mean(np.abs(res.depth - truth) / truth)) < 0.01


# --------------------------------------------------------------------------------------------
# The command


def _write_inputs(root):
    from roomlight.core.io import write_exr, write_panorama

    root.mkdir()
    names = []
    for seed in range(5):
        rad, depth = _room(seed, 32)
        write_panorama(root / f"room-{seed}.exr", (_cap(rad, 20.0), depth), metadata={"seed": seed})
        names.append(f"room-{seed}")
    rad, depth = _room(9, 32)
    (root / "sub").mkdir()
    write_panorama(root / "sub" / "x.exr", (_cap(rad, 20.0), depth))
    names.append("sub__x")
    bad_aspect = np.ones((32, 32), np.float32)
    write_exr(root / "square.exr", {"R": bad_aspect, "G": bad_aspect, "B": bad_aspect})
    nan = _room(5, 32)[0]
    nan[3, 3, 1] = np.nan
    write_exr(root / "nan.exr", {c: nan[..., i] for i, c in enumerate("RGB")}, half=False)
    neg, neg_depth = _room(6, 32)
    neg[4, 4, 0] = -1.0
    write_exr(root / "negative.exr", {**{c: neg[..., i] for i, c in enumerate("RGB")}, "Z": neg_depth}, half=False)
    (root / "garbage.exr").write_bytes(b"not an exr at all")
    write_exr(root / "nodepth.exr", {c: _room(8, 32)[0][..., i] for i, c in enumerate("RGB")})
    return names


@pytest.mark.slow
def test_prepare_command_end_to_end(tmp_path):
    from roomlight.cli.main import cli
    from roomlight.core.io import read_panorama

    inp = tmp_path / "in"
    names = _write_inputs(inp)
    out = tmp_path / "out"
    (out / ".partial").mkdir(parents=True)
    (out / ".partial" / "stale.exr").write_bytes(b"half")  # left by an interrupted run
    runner = CliRunner()
    res = runner.invoke(cli, ["prepare", str(inp), "--out", str(out), "--depth", "synthetic", "--split", "50/25/25"])
    assert res.exit_code == 1, res.output
    text = res.output
    for bad, why in [("square.exr", "width = 2 x height"), ("nan.exr", "NaN"), ("negative.exr", "negative"),
                     ("garbage.exr", "not an OpenEXR file"), ("nodepth.exr", "no depth channel")]:
        assert f"skipped {bad}:" in text and why in text.split(f"skipped {bad}:")[1].splitlines()[0], bad
    written = sorted(p for p in out.rglob("*.exr"))
    assert sorted(p.stem for p in written) == sorted(names)
    assert not (out / ".partial").exists()
    assert {p.parent.name for p in written} <= {"train", "val", "test"}
    assert (out / "stats.json").is_file() and (out / "contact_sheet.png").is_file()
    assert len(list((out / "previews").glob("*.png"))) == len(names)
    log = [json.loads(line) for line in (out / "prepare-log.jsonl").read_text().splitlines()]
    assert {r["input"] for r in log if r["status"] == "skipped"} == {
        "square.exr", "nan.exr", "negative.exr", "garbage.exr", "nodepth.exr"}
    p = read_panorama(next(out.rglob("room-0.exr")))
    assert p.depth is not None and p.metadata["source"] == "room-0.exr" and p.metadata["seed"] == 0
    prep = p.metadata["prepare"]
    assert prep["nadir"]["rows"] == 4 and prep["depth"]["kind"] == "affine"
    assert abs(math.log(math.exp(np.mean(np.log(luminance_np(p.radiance) + 1e-6))))) < 1e-3  # calibrated
    # resumable: a rerun does nothing new; a repair turns a skipped file into an output
    res = runner.invoke(cli, ["prepare", str(inp), "--out", str(out), "--depth", "synthetic", "--split", "50/25/25",
                              "--clamp-negative"])
    summary = json.loads(next(line for line in res.output.splitlines() if line.startswith("{")))
    assert summary["written"] == 1 and summary["existing"] == len(names)
    # another split would move files: refused
    res = runner.invoke(cli, ["prepare", str(inp), "--out", str(out), "--depth", "synthetic", "--split", "none"])
    assert res.exit_code == 2 and "other settings" in res.output
    # the prepared folder trains
    run = tmp_path / "run"
    res = runner.invoke(cli, ["train", "--data", str(out), "--out", str(run), "--config", "tiny", "--max-steps", "2",
                              "--set", "progress=false", "--set", "image_every=0", "--workers", "0"])
    assert res.exit_code == 0, res.output
    assert "trained to step 2/2" in res.output


def test_prepare_command_refuses_bad_options(tmp_path):
    from roomlight.cli.main import cli

    inp = tmp_path / "in"
    inp.mkdir()
    runner = CliRunner()
    for args, msg in [(["--nadir", "sideways"], "auto, off or a cap"), (["--nadir", "95"], "(0, 60]"),
                      (["--split", "80/20"], "TRAIN/VAL/TEST"), (["--res", "32x32"], "H x 2H"),
                      (["--depth", "keep", "--truth", str(inp)], "--truth")]:
        res = runner.invoke(cli, ["prepare", str(inp), "--out", str(tmp_path / "o"), *args])
        assert res.exit_code == 2 and msg in res.output, (args, res.output)
    res = runner.invoke(cli, ["prepare", str(inp), "--out", str(tmp_path / "o")])
    assert res.exit_code == 2 and "contains no .exr or .hdr panorama" in res.output


@pytest.mark.mitsuba
def test_synth_nadir_cap_blacks_out_exactly_the_cap(mi):
    from roomlight.datagen.synth.dataset import render_room

    rad0, depth0, meta0 = render_room(3, height=16, spp=4)
    rad1, depth1, meta1 = render_room(3, height=16, spp=4, nadir_cap=25.0)
    theta = (np.arange(16) + 0.5) / 16 * 180
    cap = theta > 155.0
    assert float(rad1[cap].abs().max()) == 0.0
    # elsewhere the same render, up to the calibration factor
    a = rad0[~cap].numpy() * meta0["exposure_factor"]
    b = rad1[~cap].numpy() * meta1["exposure_factor"]
    np.testing.assert_allclose(a, b, rtol=1e-4, atol=1e-6)
    assert torch.equal(depth0, depth1)
