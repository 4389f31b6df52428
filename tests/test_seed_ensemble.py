"""scripts/seed_ensemble.py: several fits' probe predictions averaged, on hand-made runs whose probe renders are
known multiples of their truth (their average is then a known multiple too)."""

from __future__ import annotations

import json
import math
from types import SimpleNamespace

import numpy as np
import pytest

from helpers_scripts import load_script

MATERIALS = ("diffuse", "matte", "mirror")


def _write_rgb(path, image: np.ndarray) -> None:
    from roomlight.core.io.exr import write_exr

    write_exr(path, {c: image[..., k] for k, c in enumerate("RGB")})


def _psnr_ldr(pred: np.ndarray, target: np.ndarray, inside: np.ndarray) -> float:
    """The slow obvious reference: gamma 2.2, clipped to [0, 1], mean squared error over the pixels' channels."""
    def ldr(x):
        return np.clip(x, 0.0, None) ** (1.0 / 2.2)
    p, t = np.clip(ldr(pred[inside]), 0, 1), np.clip(ldr(target[inside]), 0, 1)
    return 10.0 * math.log10(1.0 / float(np.mean((p - t) ** 2)))


@pytest.fixture
def runs(tmp_path, monkeypatch):
    """Two photos and two runs: run `one` renders every probe at `factors[0]` of the truth, run `two` at
    `factors[1]`; photo c is finished in run one only."""
    rng = np.random.default_rng(5)
    mask = np.zeros((6, 8), np.int32)
    mask[1:5, 2:7] = 1
    factors = {"photo-a": (0.5, 1.0), "photo-b": (0.4, 0.4), "photo-c": (1.0, None)}
    truths = {}
    for photo, (f1, f2) in factors.items():
        images = {m: rng.uniform(0.05, 0.5, (6, 8, 3)).astype(np.float32) for m in MATERIALS}
        truths[str(tmp_path / "bench" / photo)] = SimpleNamespace(window_mask=mask, probe_images=images)
        for run, f in (("one", f1), ("two", f2)):
            if f is None:
                continue
            folder = tmp_path / run / "cases" / photo / "prior"
            folder.mkdir(parents=True)
            (folder / "result.json").write_text(json.dumps({"case_dir": str(tmp_path / "bench" / photo)}))
            for m, im in images.items():
                _write_rgb(folder / f"probes_{m}.exr", f * im)
    monkeypatch.setattr("roomlight.evaluation.photobench.scoring.load_truth", lambda case_dir: truths[str(case_dir)])
    return tmp_path, truths


def test_the_average_scores_the_averaged_render(runs):
    root, truths = runs
    script = load_script("seed_ensemble")
    scores = script.ensemble_scores([root / "one", root / "two"], "prior")
    assert sorted(scores) == ["photo-a", "photo-b"]           # photo c is not in both runs
    truth = truths[str(root / "bench" / "photo-a")]
    inside, gt = truth.window_mask > 0, truth.probe_images["matte"]
    a = scores["photo-a"]["matte"]
    # 0.5 and 1.0 of the truth average to 0.75 of it
    assert a["average"]["psnr_ldr"] == pytest.approx(_psnr_ldr(0.75 * gt, gt, inside), rel=1e-5)
    assert a["members"][0]["psnr_ldr"] == pytest.approx(_psnr_ldr(0.5 * gt, gt, inside), rel=1e-5)
    assert math.isinf(a["members"][1]["psnr_ldr"])           # run two renders photo a's truth itself
    # a scaled light keeps every pixel's colour: no angular error, members and mean alike
    assert a["average"]["angular_error"] == pytest.approx(0.0, abs=1e-3)
    # photo a's infinite member leaves it out of the paired difference: photo b alone, whose members agree
    summ = script.summary(scores)["matte"]["psnr_ldr"]
    assert summ["n"] == 1 and summ["mean"] == pytest.approx(0.0, abs=1e-9)


def test_runs_of_other_photographs_or_one_run_twice_are_refused(runs):
    root, _ = runs
    script = load_script("seed_ensemble")
    with pytest.raises(SystemExit, match="given twice"):
        script.ensemble_scores([root / "one", root / "one"], "prior")
    record = root / "two" / "cases" / "photo-b" / "prior" / "result.json"
    record.write_text(json.dumps({"case_dir": str(root / "bench" / "photo-a")}))
    with pytest.raises(SystemExit, match="photo-b: the runs fitted different photographs"):
        script.ensemble_scores([root / "one", root / "two"], "prior")


def test_equal_members_gain_nothing_and_the_summary_pairs_per_photo(runs, capsys, tmp_path):
    root, truths = runs
    script = load_script("seed_ensemble")
    truth = truths[str(root / "bench" / "photo-a")]
    inside, gt = truth.window_mask > 0, truth.probe_images["diffuse"]
    # photo a's second member 1.3 of the truth instead of the truth itself: their average is 0.9 of it
    for m in MATERIALS:
        _write_rgb(root / "two" / "cases" / "photo-a" / "prior" / f"probes_{m}.exr", 1.3 * truth.probe_images[m])
    scores = script.ensemble_scores([root / "one", root / "two"], "prior")
    b = scores["photo-b"]["diffuse"]
    assert b["average"]["psnr_ldr"] == pytest.approx(b["members"][0]["psnr_ldr"], rel=1e-6)   # 0.4 and 0.4
    gain_a = _psnr_ldr(0.9 * gt, gt, inside) - 0.5 * (_psnr_ldr(0.5 * gt, gt, inside) + _psnr_ldr(1.3 * gt, gt, inside))
    assert gain_a > 0
    summ = script.summary(scores)["diffuse"]["psnr_ldr"]
    assert summ["n"] == 2 and summ["wins"] == 1                # photo b's difference is zero: not a win
    assert summ["mean"] == pytest.approx(gain_a / 2, rel=1e-4)
    assert summ["ci95"][0] == pytest.approx(0.0, abs=1e-6) and summ["ci95"][1] == pytest.approx(gain_a, rel=1e-4)
    script.main([str(root / "one"), str(root / "two"), "--json", str(tmp_path / "e.json")])
    out = capsys.readouterr().out
    assert "2 photos, method prior, the probes averaged over 2 fits" in out
    assert "| diffuse | psnr_ldr |" in out
    assert json.loads((tmp_path / "e.json").read_text())["summary"]["diffuse"]["psnr_ldr"]["n"] == 2
    with pytest.raises(SystemExit):
        script.main([str(root / "one")])                     # one run is not an ensemble
    with pytest.raises(SystemExit, match="not a run-photos folder"):
        script.main([str(root / "one"), str(tmp_path / "nothing")])
