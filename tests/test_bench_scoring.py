"""The synthetic benchmark's scoring: metrics, camera recording, tables and paired statistics (no rendering)."""

import json
import math
from pathlib import Path

import numpy as np
import pytest
import torch

from roomlight.evaluation.harness.errors import BenchError
from roomlight.evaluation.harness.metrics import angular_error_deg, psnr_ldr, rmse_hdr, score_view
from roomlight.evaluation.bench.recording import exposure_for, record_ldr, saturated_fraction
from roomlight.errors import RoomlightError, ShapeError


def img(*pixels):
    """A (1, N, 3) float64 image from N RGB triples."""
    return np.array([pixels], dtype=np.float64)


# ----------------------------------------------------------------------------------- metrics
def test_psnr_ldr_hand_computed():
    half = 0.5 ** 2.2  # displays as exactly 0.5
    gt = img((0, 0, 0), (0.3, 0.3, 0.3), (9, 9, 9))
    pred = img((half, half, half), (0.3, 0.3, 0.3), (100, 0, 9))
    mask = np.array([[True, True, False]])
    # Pixel 0 differs by 0.5 in each channel, pixel 1 not at all: MSE = 3 * 0.25 / 6 = 0.125.
    assert psnr_ldr(pred, gt, mask) == pytest.approx(10 * math.log10(1 / 0.125))
    # Pixel 2 (masked out) would count: values above 1 clip, so only G differs, by 1.
    all_px = (3 * 0.25 + 1.0) / 9
    assert psnr_ldr(pred, gt) == pytest.approx(10 * math.log10(1 / all_px))
    assert psnr_ldr(gt, gt, mask) == math.inf
    # Torch inputs and an integer mask give the same numbers.
    assert psnr_ldr(torch.tensor(pred), torch.tensor(gt), torch.tensor(mask.astype(np.uint8))) == pytest.approx(
        10 * math.log10(8))


def test_rmse_hdr_hand_computed():
    gt = img((1, 2, 3), (0, 0, 0))
    pred = img((1, 2, 5), (100, 100, 100))
    assert rmse_hdr(pred, gt, np.array([[True, False]])) == pytest.approx(math.sqrt(4 / 3))
    assert rmse_hdr(pred, gt) == pytest.approx(math.sqrt((4 + 3 * 100 ** 2) / 6))


def test_angular_error_hand_computed():
    gt = img((1, 0, 0), (1, 0, 0), (1, 1, 1), (0, 0, 0), (0, 0, 0), (0, 2, 0))
    pred = img((0, 1, 0), (1, 1, 0), (2, 2, 2), (0, 0, 0), (1, 2, 3), (0, 0, 0))
    each = [90.0, 45.0, 0.0, 0.0, 90.0, 90.0]
    assert angular_error_deg(pred, gt) == pytest.approx(np.mean(each))
    assert angular_error_deg(pred, gt, np.array([[1, 1, 1, 0, 0, 0]])) == pytest.approx(45.0)
    # Accurate for tiny angles: (1, 1e-6, 0) vs (1, 0, 0) is 1e-6 rad.
    assert angular_error_deg(img((1, 1e-6, 0)), img((1, 0, 0))) == pytest.approx(math.degrees(1e-6), rel=1e-6)


def test_metric_input_errors():
    a = img((1, 1, 1), (1, 1, 1))
    with pytest.raises(RoomlightError, match="metrics: the mask selects no pixel"):
        psnr_ldr(a, a, np.zeros((1, 2), bool))
    with pytest.raises(ShapeError, match=r"metrics: expected two \(H, W, 3\) images of the same shape"):
        rmse_hdr(a, img((1, 1, 1)))
    with pytest.raises(ShapeError, match=r"metrics: mask is \(2, 1\), images are \(1, 2\)"):
        angular_error_deg(a, a, np.ones((2, 1), bool))
    s = score_view(a, a * 2, np.ones((1, 2), bool))
    assert s["pixels"] == 2 and s["rmse_hdr"] == pytest.approx(1.0) and s["angular_error"] == pytest.approx(0.0)


# ----------------------------------------------------------------------------------- recording
def test_exposure_rule_and_recording():
    hdr = np.zeros((2, 2, 3))
    hdr[0] = 0.5  # luminance 0.5 (weights sum to 1)
    hdr[1] = 8.0
    mask = np.array([[True, True], [False, False]])
    k = exposure_for(hdr, mask)
    assert k == pytest.approx(0.18 / (0.5 + 1e-6))
    ldr = record_ldr(np.array([[[0.0, 0.5 ** 2.2, 1.0], [7.0, -1.0, np.nan]]]))
    assert ldr.dtype == np.uint8
    assert ldr.tolist() == [[[0, 128, 255], [255, 0, 0]]]
    assert saturated_fraction(record_ldr(hdr * k), np.ones((2, 2), bool)) == pytest.approx(0.5)
    with pytest.raises(RoomlightError, match="exposure: the object mask is empty"):
        exposure_for(hdr, np.zeros((2, 2), bool))


# ----------------------------------------------------------------------------------- report
def _fake_results(root: Path, rows):
    for scene, material, method, psnr, rmse, ang in rows:
        d = root / "cases" / scene / material / method
        d.mkdir(parents=True)
        m = {"psnr_ldr": psnr, "rmse_hdr": rmse, "angular_error": ang, "pixels": 10}
        (d / "result.json").write_text(json.dumps({
            "scene": f"{scene}/{material}", "panorama": scene, "material": material, "method": method,
            "emitter_kind": "envmap" if method.endswith("envmap") else "mesh",
            "metrics": {"eval": m, "input": m}, "fit_seconds": 2.0}))


def test_report_tables_hand_computed(tmp_path):
    from roomlight.evaluation.bench.report import markdown_table, write_report

    _fake_results(tmp_path, [
        ("r1", "diffuse", "prior", 20.0, 0.1, 1.0), ("r2", "diffuse", "prior", 30.0, 0.3, 3.0),
        ("r1", "diffuse", "direct-envmap", 10.0, 0.5, 2.0), ("r2", "diffuse", "direct-envmap", 10.0, 0.7, 1.0),
        ("r1", "mirror", "prior", 15.0, 2.0, 4.0),
    ])
    paths = write_report(tmp_path, figures=False, progress=False)
    summary = json.loads(paths["json"].read_text())
    cell = summary["views"]["eval"]["prior"]["diffuse"]["psnr_ldr"]
    assert cell == {"mean": 25.0, "std": 5.0, "n": 2}
    assert summary["views"]["eval"]["direct-envmap"]["diffuse"]["rmse_hdr"]["mean"] == pytest.approx(0.6)
    md = markdown_table([json.loads(p.read_text()) for p in sorted(tmp_path.rglob("result.json"))], "eval")
    lines = md.splitlines()
    assert lines[0].startswith("| Method | Emitter | PSNR LDR ↑ diffuse | PSNR LDR ↑ mirror | RMSE HDR ↓ diffuse")
    # Rows in the paper's order (smoothness baselines first); best per column in bold.
    assert lines[2].startswith("| direct-envmap | Env map | 10.00 ± 0.00 | – | 0.600 ± 0.100 |")
    # mirror has one scene: its value alone, no "± 0.00"
    assert lines[3].startswith("| prior | 2.5D AL | **25.00 ± 5.00** | 15.00 | **0.200 ± 0.100** |")
    # Angular error: lower is better, so the env map's 1.5 wins over the prior's 2.0.
    assert "| **1.500 ± 0.500** |" in lines[2] and "| 2.000 ± 1.000 |" in lines[3]
    import csv

    with open(paths["csv"]) as fh:
        rows = list(csv.DictReader(fh))
    prior = next(r for r in rows if r["method"] == "prior")
    assert float(prior["psnr_ldr_diffuse_mean"]) == 25.0 and float(prior["psnr_ldr_diffuse_std"]) == 5.0
    assert prior["psnr_ldr_mirror_n"] == "1"
    with open(paths["cases"]) as fh:
        assert len(list(csv.DictReader(fh))) == 10  # 5 cases x 2 views
    assert "Table 2" in paths["markdown"].read_text() and paths["html"].is_file()


def test_paired_differences_hand_computed(tmp_path):
    """Per-scene differences prior - baseline: pairing by scene, win counts with the metric's
    direction, scenes missing on either side left out; the report carries them."""
    from roomlight.evaluation.bench.report import write_report

    _fake_results(tmp_path, [
        ("r1", "diffuse", "prior", 20.0, 0.1, 1.0), ("r2", "diffuse", "prior", 30.0, 0.3, 3.0),
        ("r3", "diffuse", "prior", 12.0, 0.9, 5.0),
        ("r1", "diffuse", "direct-envmap", 10.0, 0.5, 2.0), ("r2", "diffuse", "direct-envmap", 10.0, 0.7, 1.0),
        ("r1", "diffuse", "oracle", 40.0, 0.0, 0.0),  # never a baseline
    ])
    paths = write_report(tmp_path, figures=False, progress=False)
    summary = json.loads(paths["json"].read_text())
    paired = summary["paired"]["eval"]
    assert set(paired) == {"direct-envmap"}
    psnr = paired["direct-envmap"]["diffuse"]["psnr_ldr"]
    assert psnr["n"] == 2 and psnr["mean"] == pytest.approx(15.0) and psnr["wins"] == 2  # +10, +20
    lo, hi = psnr["ci95"]
    assert 10.0 <= lo <= 15.0 <= hi <= 20.0
    rmse = paired["direct-envmap"]["diffuse"]["rmse_hdr"]
    assert rmse["mean"] == pytest.approx(-0.4) and rmse["wins"] == 2 and rmse["better"] == "lower"
    ang = paired["direct-envmap"]["diffuse"]["angular_error"]
    assert ang["mean"] == pytest.approx(0.5) and ang["wins"] == 1  # -1 (win) and +2 (loss)
    md = paths["markdown"].read_text()
    assert "| direct-envmap | Δ PSNR LDR (dB, ↑) | +15.00 [" in md and "2/2 ✓" in md
    page = paths["html"].read_text()
    assert "Paired differences" in page
    # the note that explains the cells comes once per page, however many paired tables there are
    assert md.count("Cells: mean per-scene difference") == 1
    assert page.count("Cells: mean per-scene difference") == 1


def test_paired_differences_by_cluster_average_within_each_group_first():
    """Scenes grouped by ``cluster`` (objects of one photo): the mean, the interval, the wins and n are over
    the groups' mean differences, computed here by hand, not over the scenes one by one."""
    from roomlight.evaluation.harness.paired import bootstrap_mean_interval, paired_differences

    scores = {  # scene: (a, b) object PSNR; photo p1 has two objects, p2 three, p3 one
        "p1/o1": (20.0, 18.0), "p1/o2": (22.0, 21.0),
        "p2/o1": (15.0, 16.0), "p2/o2": (14.0, 17.0), "p2/o3": (18.0, 18.0),
        "p3/o1": (25.0, 19.0)}
    records = [{"scene": sc, "material": "objects", "method": m, "metrics": {"insert": {"object_psnr_ldr": v}}}
               for sc, (a, b) in scores.items() for m, v in (("a", a), ("b", b))]
    records.append({"scene": "p3/o2", "material": "objects", "method": "a",  # unpaired: left out
                    "metrics": {"insert": {"object_psnr_ldr": 40.0}}})
    kw = dict(exclude=(), metrics=("object_psnr_ldr",), higher_is_better={"object_psnr_ldr": True})
    per_object = paired_differences(records, "a", "insert", **kw)["b"]["objects"]["object_psnr_ldr"]
    by_photo = paired_differences(records, "a", "insert", cluster=lambda scene: scene.split("/")[0],
                                  **kw)["b"]["objects"]["object_psnr_ldr"]
    photo_means = [(2.0 + 1.0) / 2, (-1.0 - 3.0 + 0.0) / 3, 6.0]
    assert per_object["n"] == 6 and per_object["mean"] == pytest.approx(5.0 / 6)
    assert by_photo["n"] == 3 and by_photo["wins"] == 2
    assert by_photo["mean"] == pytest.approx(np.mean(photo_means))
    assert by_photo["ci95"] == pytest.approx(list(bootstrap_mean_interval(photo_means)))
    # without a cluster each scene is its own group: the per-object statistics
    assert per_object["ci95"] == pytest.approx(list(bootstrap_mean_interval([2.0, 1.0, -1.0, -3.0, 0.0, 6.0])))


def test_paired_tables_against_another_reference_method(tmp_path):
    """``reference``: any method's per-scene differences against the others, hand-computed; a
    method without finished cases is refused with the methods the results do have."""
    from roomlight.evaluation.harness.errors import BenchError
    from roomlight.evaluation.bench.report import write_report

    _fake_results(tmp_path, [
        ("r1", "diffuse", "prior", 20.0, 0.1, 1.0), ("r2", "diffuse", "prior", 30.0, 0.3, 3.0),
        ("r1", "diffuse", "veni", 10.0, 0.5, 2.0), ("r2", "diffuse", "veni", 10.0, 0.7, 1.0),
        ("r1", "diffuse", "veni-d", 14.0, 0.2, 2.5), ("r2", "diffuse", "veni-d", 11.0, 0.6, 0.5),
    ])
    paths = write_report(tmp_path, figures=False, progress=False, reference="veni-d")
    summary = json.loads(paths["json"].read_text())
    assert summary["paired_reference"] == "veni-d"
    paired = summary["paired"]["eval"]
    assert set(paired) == {"prior", "veni"}
    vs_veni = paired["veni"]["diffuse"]
    assert vs_veni["psnr_ldr"]["mean"] == pytest.approx(2.5) and vs_veni["psnr_ldr"]["wins"] == 2  # +4, +1
    assert vs_veni["rmse_hdr"]["mean"] == pytest.approx(-0.2) and vs_veni["rmse_hdr"]["wins"] == 2
    assert vs_veni["angular_error"]["mean"] == pytest.approx(0.0) and vs_veni["angular_error"]["wins"] == 1
    vs_prior = paired["prior"]["diffuse"]["psnr_ldr"]
    assert vs_prior["mean"] == pytest.approx(-12.5) and vs_prior["wins"] == 0  # -6, -19
    md = paths["markdown"].read_text()
    assert "evaluation view: veni-d against each other method" in md and "| veni-d − baseline |" in md
    assert "veni-d against each other method" in paths["html"].read_text()
    with pytest.raises(BenchError, match="'venid' to pair the others with; the results have prior, veni, veni-d"):
        write_report(tmp_path, figures=False, progress=False, reference="venid")


def test_bootstrap_interval_matches_the_normal_approximation():
    """For many scenes the percentile bootstrap of a mean approaches mean +- 1.96 s / sqrt(n)
    (s: the population standard deviation, which is what the bootstrap resamples)."""
    from roomlight.core.stats import bootstrap_mean_interval

    x = np.random.default_rng(3).normal(1.0, 2.0, 400)
    lo, hi = bootstrap_mean_interval(x)
    half = 1.96 * x.std() / np.sqrt(x.size)
    assert lo == pytest.approx(x.mean() - half, abs=0.05 * half)
    assert hi == pytest.approx(x.mean() + half, abs=0.05 * half)
    assert bootstrap_mean_interval([2.5]) == (2.5, 2.5)
    assert bootstrap_mean_interval(x) == (lo, hi)  # seeded


def test_interval_verdict_reads_the_side_of_zero_by_hand():
    from roomlight.core.stats import interval_verdict

    assert interval_verdict(0.1, 0.5, 10, higher_is_better=True) == 1
    assert interval_verdict(0.1, 0.5, 10, higher_is_better=False) == -1
    assert interval_verdict(-0.5, -0.1, 10, higher_is_better=False) == 1
    assert interval_verdict(-0.5, -0.1, 10, higher_is_better=True) == -1
    assert interval_verdict(-0.1, 0.5, 10, higher_is_better=True) == 0
    assert interval_verdict(0.0, 0.5, 10, higher_is_better=True) == 0  # touching zero decides nothing
    assert interval_verdict(0.3, 0.3, 1, higher_is_better=True) == 0  # one item: a zero-width interval


def test_report_without_results_fails_cleanly(tmp_path):
    from roomlight.evaluation.bench.report import write_report

    with pytest.raises(BenchError, match="no results"):
        write_report(tmp_path)


def _compare_script():
    """scripts/compare_bench_runs.py loaded as a module."""
    from helpers_scripts import load_script

    return load_script("compare_bench_runs")


def test_two_runs_compared_scene_by_scene(tmp_path, capsys):
    """scripts/compare_bench_runs.py: the second run's prior against the first run's methods, paired by scene."""
    mod = _compare_script()
    _fake_results(tmp_path / "a", [("r1", "matte", "prior", 20.0, 0.1, 4.0), ("r2", "matte", "prior", 22.0, 0.3, 6.0),
                                   ("r1", "matte", "direct-sphere", 21.0, 0.2, 3.0),
                                   ("r2", "matte", "direct-sphere", 21.0, 0.2, 3.0)])
    _fake_results(tmp_path / "b", [("r1", "matte", "prior", 21.0, 0.1, 2.0), ("r2", "matte", "prior", 22.5, 0.3, 3.0)])
    mod.main([str(tmp_path / "a"), str(tmp_path / "b"), "--out", str(tmp_path / "cmp.md")])
    md = (tmp_path / "cmp.md").read_text()
    # prior+wb - prior: PSNR +1.0 and +0.5 (mean +0.75), angle -2 and -3 (mean -2.5, both won)
    assert "| prior | Δ PSNR LDR (dB, ↑) | +0.75 [" in md and "| prior | Δ angular error (°, ↓) | -2.500 [" in md
    # prior+wb - direct-sphere: angle -1 and 0 (mean -0.5, one win)
    assert "| direct-sphere | Δ angular error (°, ↓) | -0.500 [" in md and " 1/2" in md


def _fake_photo_run(res: Path, cases) -> None:
    """A photo benchmark results folder: cases (photo, method, diffuse PSNR, [region PSNR per inserted object])."""
    import json

    res.mkdir(parents=True)
    (res / "run.json").write_text(json.dumps({"kind": "photos"}))
    for photo, method, psnr, regions in cases:
        folder = res / "cases" / photo / method
        folder.mkdir(parents=True)
        probes = {m: {"psnr_ldr": psnr, "rmse_hdr": 0.1, "angular_error": 3.0} for m in ("diffuse", "matte", "mirror")}
        insertion = [{"id": f"insert{k + 1}", "visible": True, "distance_m": 2.0 + k, "psnr_ldr": v, "ssim": 0.5,
                      "object_psnr_ldr": v - 3.0, "rmse_hdr": 0.2} for k, v in enumerate(regions)]
        (folder / "result.json").write_text(json.dumps({"photo": photo, "method": method, "probes": probes,
                                                         "insertion": insertion}))


def test_two_photo_runs_compared_object_by_object_for_insertion(tmp_path):
    """On a photo benchmark the inserted objects are paired per photo and object, not per photo."""
    mod = _compare_script()
    _fake_photo_run(tmp_path / "a", [("p1", "prior", 15.0, [20.0, 22.0]), ("p2", "prior", 16.0, [18.0, 25.0])])
    _fake_photo_run(tmp_path / "b", [("p1", "prior", 17.0, [21.0, 22.0]), ("p2", "prior", 16.5, [20.0, 24.0])])
    mod.main([str(tmp_path / "a"), str(tmp_path / "b"), "--suffix", "+ap", "--out", str(tmp_path / "cmp.md")])
    md = (tmp_path / "cmp.md").read_text()
    # probes per photo: +2.0 and +0.5, mean +1.25
    assert "| prior | Δ PSNR LDR (dB, ↑) | +1.25 [" in md
    # inserted objects: +1, 0, +2, -1 over four objects, mean +0.50, two won
    section = md.split("## The inserted objects (paired per object)")[1].split("## ")[0]
    assert "| prior | Δ region PSNR LDR ↑ | +0.50 [" in section and " 2/4" in section
    # and per photo: p1 (+1 + 0) / 2 = +0.5, p2 (+2 - 1) / 2 = +0.5, both won
    by_photo = md.split("## The inserted objects (paired per photo")[1]
    assert "| prior | Δ region PSNR LDR ↑ | +0.50 [+0.50, +0.50] 2/2" in by_photo


def test_repeated_runs_averaged_score_by_score():
    """mean_over_runs: each (scene, method, material) score averaged over the runs; a scene any run lacks is
    left out; a score another run lacks is nan (not a mean over fewer runs); non-numbers are dropped."""
    from roomlight.evaluation.harness.paired import mean_over_runs

    def rec(scene, psnr, angle, extra=None):
        return {"scene": scene, "method": "prior", "material": "diffuse", "note": scene,
                "metrics": {"eval": {"psnr_ldr": psnr, "angular_error": angle, **(extra or {})}}}

    one = [rec("p1", 20.0, 4.0, {"label": "x", "flag": True}), rec("p2", 10.0, 8.0, {"rmse_hdr": 0.2}),
           rec("p3", 5.0, 1.0)]
    two = [rec("p1", 23.0, 2.0, {"label": "y"}), rec("p2", 11.0, 6.0, {"only_here": 1.0})]
    three = [rec("p1", 26.0, 3.0), rec("p2", 15.0, 7.0)]
    merged = {r["scene"]: r for r in mean_over_runs([one, two, three])}
    assert sorted(merged) == ["p1", "p2"]                      # p3 is in run one only
    assert merged["p1"]["metrics"]["eval"] == {"psnr_ldr": 23.0, "angular_error": 3.0}
    p2 = merged["p2"]["metrics"]["eval"]
    assert (p2["psnr_ldr"], p2["angular_error"]) == (12.0, 7.0) and math.isnan(p2["rmse_hdr"])
    assert "only_here" not in p2                               # the first run's scores decide which are kept
    assert merged["p1"]["note"] == "p1"
    assert mean_over_runs([one])[2]["metrics"]["eval"]["psnr_ldr"] == 5.0
    with pytest.raises(ValueError):
        mean_over_runs([])


def test_compared_runs_averaged_over_seeds(tmp_path):
    """compare_bench_runs.py A,A2 B,B2: each side's scores are the means over its runs before pairing."""
    mod = _compare_script()
    _fake_photo_run(tmp_path / "a", [("p1", "prior", 15.0, [20.0]), ("p2", "prior", 16.0, [18.0])])
    _fake_photo_run(tmp_path / "a2", [("p1", "prior", 17.0, [22.0]), ("p2", "prior", 18.0, [18.0])])
    _fake_photo_run(tmp_path / "b", [("p1", "prior", 17.0, [21.0]), ("p2", "prior", 16.5, [20.0])])
    _fake_photo_run(tmp_path / "b2", [("p1", "prior", 19.0, [21.0]), ("p2", "prior", 17.5, [22.0])])
    mod.main([f"{tmp_path / 'a'},{tmp_path / 'a2'}", f"{tmp_path / 'b'},{tmp_path / 'b2'}", "--suffix", "+x",
              "--out", str(tmp_path / "cmp.md")])
    md = (tmp_path / "cmp.md").read_text()
    # probes: a means 16, 17; b means 18, 17; differences +2 and 0, mean +1.00, one won
    assert "| prior | Δ PSNR LDR (dB, ↑) | +1.00 [+0.00, +2.00] 1/2" in md
    # objects: a 21, 18; b 21, 21: differences 0 and +3
    section = md.split("## The inserted objects (paired per object)")[1].split("## ")[0]
    assert "| prior | Δ region PSNR LDR ↑ | +1.50 [+0.00, +3.00] 1/2" in section
    with pytest.raises(SystemExit, match="not a results folder"):
        mod.main([f"{tmp_path / 'a'},{tmp_path / 'none'}", str(tmp_path / "b")])
    with pytest.raises(SystemExit, match="given twice"):
        mod.main([f"{tmp_path / 'a'},{tmp_path / 'a'}", str(tmp_path / "b")])


def test_slope_and_its_bootstrap_interval():
    """bootstrap_slope_interval: exact on a line (every resample with two distinct x has the same slope), the
    least-squares slope of noisy points inside its interval, nan without two distinct x."""
    from roomlight.core.stats import bootstrap_slope_interval

    x = np.array([1.0, 2.0, 3.0, 5.0, 8.0])
    slope, lo, hi = bootstrap_slope_interval(x, 2.0 * x + 1.0)
    assert (slope, lo, hi) == (pytest.approx(2.0), pytest.approx(2.0), pytest.approx(2.0))
    rng = np.random.default_rng(1)
    xs = rng.uniform(0, 4, 40)
    ys = -0.5 * xs + rng.normal(0, 0.3, 40)
    slope, lo, hi = bootstrap_slope_interval(xs, ys)
    # the closed-form least-squares slope, computed apart
    ref = float(((xs - xs.mean()) * (ys - ys.mean())).sum() / ((xs - xs.mean()) ** 2).sum())
    assert slope == pytest.approx(ref) and lo < ref < hi and hi - lo < 0.5
    assert all(math.isnan(v) for v in bootstrap_slope_interval([2.0, 2.0, 2.0], [1.0, 2.0, 3.0]))


def test_the_slope_bootstrap_resamples_whole_clusters():
    """Two photos, each with objects on a line of slope 1 at its own offset (a light per photo that is
    brighter or dimmer throughout): any draw of whole photos has slope exactly 1, so the clustered interval
    is [1, 1]; drawing objects apart mixes one photo's near object with the other's far one (slope 11 or
    -9), so that interval is wide. One object per cluster gives the object bootstrap draw for draw."""
    from roomlight.core.stats import bootstrap_slope_interval

    x = np.array([0.0, 1.0, 0.0, 1.0])
    y = np.array([0.0, 1.0, 10.0, 11.0])
    photos = ["a", "a", "b", "b"]
    assert bootstrap_slope_interval(x, y, clusters=photos) == (pytest.approx(1.0), pytest.approx(1.0),
                                                              pytest.approx(1.0))
    slope, lo, hi = bootstrap_slope_interval(x, y)
    assert slope == pytest.approx(1.0) and lo < -5.0 and hi > 5.0
    rng = np.random.default_rng(3)
    xs, ys = rng.uniform(0, 4, 12), rng.normal(0, 1, 12)
    assert bootstrap_slope_interval(xs, ys, clusters=list(range(12))) == bootstrap_slope_interval(xs, ys)
    with pytest.raises(ValueError, match="one label per pair"):
        bootstrap_slope_interval(xs, ys, clusters=[0, 1])
    # one photo is no sample of photos: no interval rather than a zero-width one
    slope, lo, hi = bootstrap_slope_interval(x, y, clusters=["a"] * 4)
    assert slope == pytest.approx(1.0) and math.isnan(lo) and math.isnan(hi)
    # labels are compared as they are: tuples are labels, 1 and "1" are two photos
    assert bootstrap_slope_interval(x, y, clusters=[("s", 1), ("s", 1), ("s", 2), ("s", 2)])[1] == pytest.approx(1.0)


def test_the_photo_reports_distance_slope_is_also_resampled_by_photo():
    """Two photos whose objects gain 1 dB per metre over their own offsets (0 and 10 dB): the slope is 1, over
    photos its interval is exactly [1, 1] (any draw of whole photos keeps both lines intact), over objects
    it spans the mixes of one photo's near object with the other's far one."""
    from roomlight.evaluation.photobench.report import insertion_summary

    records = []
    for photo, offset in (("photo-00000", 0.0), ("photo-00001", 10.0)):
        for obj, d in (("insert1", 1.0), ("insert2", 2.0)):
            for method, psnr in (("prior", 20.0 + offset + d), ("prior-envmap", 20.0)):
                records.append({"scene": f"{photo}/{obj}", "material": "objects", "method": method,
                                "distance_m": d, "metrics": {"insert": {"psnr_ldr": psnr}}})
    d = insertion_summary(records)["distance"]
    assert d["slope_db_per_m"] == pytest.approx(1.0)
    assert d["slope_ci95_by_photo"] == [pytest.approx(1.0), pytest.approx(1.0)]
    assert d["slope_ci95"][0] < -5.0 and d["slope_ci95"][1] > 5.0
