"""scripts/photo_brightness.py: the exposure oracle of a photo benchmark run, on a hand-made results folder
whose recovered probes are known multiples of their truth."""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from helpers_scripts import load_script


def _script():
    return load_script("photo_brightness")


def _write_rgb(path: Path, image: np.ndarray) -> None:
    from roomlight.core.io.exr import write_exr

    write_exr(path, {c: image[..., k] for k, c in enumerate("RGB")})


@pytest.fixture
def run(tmp_path, monkeypatch):
    """Two photos; `dim` renders every probe at half (photo a) or a quarter (photo b) of the truth, `off`
    renders the diffuse probe at its truth and the mirror probe as something else."""
    rng = np.random.default_rng(3)
    mask = np.zeros((6, 8), np.int32)
    mask[1:5, 2:7] = 1
    truths = {}
    for photo, factor in (("photo-a", 0.5), ("photo-b", 0.25)):
        images = {m: rng.uniform(0.05, 0.6, (6, 8, 3)).astype(np.float32) for m in ("diffuse", "matte", "mirror")}
        truths[str(tmp_path / "bench" / photo)] = SimpleNamespace(window_mask=mask, probe_images=images)
        for method, renders in (("dim", {m: factor * im for m, im in images.items()}),
                                ("off", {**images, "mirror": images["mirror"][::-1, ::-1].copy()})):
            folder = tmp_path / "res" / "cases" / photo / method
            folder.mkdir(parents=True)
            (folder / "result.json").write_text(json.dumps({"case_dir": str(tmp_path / "bench" / photo)}))
            for m, im in renders.items():
                _write_rgb(folder / f"probes_{m}.exr", im)
    monkeypatch.setattr("roomlight.evaluation.photobench.scoring.load_truth", lambda case_dir: truths[str(case_dir)])
    return tmp_path / "res", truths


def test_the_brightness_ratio_and_the_rescaled_scores(run):
    from roomlight.evaluation.harness.metrics import score_view

    res, truths = run
    table = _script().brightness_table(res, ["dim", "off"])
    assert table["dim"]["photos"] == ["photo-a", "photo-b"]
    assert table["dim"]["ratio"] == pytest.approx([0.5, 0.25], rel=1e-6)
    assert table["off"]["ratio"] == pytest.approx([1.0, 1.0], rel=1e-6)
    # rescaled by the true factor, a render that is a multiple of the truth scores as the truth itself would
    for truth, fitted, rescaled in zip(truths.values(), table["dim"]["fitted"]["matte"], table["dim"]["rescaled"]["matte"]):
        inside = truth.window_mask > 0
        half = score_view(0.5 * truth.probe_images["matte"], truth.probe_images["matte"], inside)["psnr_ldr"]
        assert fitted <= half + 1e-6                # a half or a quarter of the light scores below the truth
        assert rescaled > fitted + 3.0              # and rescaling recovers it
    # the rescaling leaves a light of the right brightness alone, mirror error included
    truth = truths[next(iter(truths))]
    wrong = score_view(truth.probe_images["mirror"][::-1, ::-1], truth.probe_images["mirror"], truth.window_mask > 0)
    assert table["off"]["fitted"]["mirror"][0] == pytest.approx(wrong["psnr_ldr"], rel=1e-6)
    assert table["off"]["rescaled"]["mirror"][0] == pytest.approx(wrong["psnr_ldr"], rel=1e-5)


def test_the_table_prints_and_a_copy_without_images_is_refused(run, capsys, tmp_path):
    res, _ = run
    script = _script()
    script.main([str(res), "--methods", "dim", "--json", str(tmp_path / "b.json")])
    out = capsys.readouterr().out
    assert "| dim | 0.35, 0.35 | 1.50 | 2/2 |" in out     # geometric mean and median of 0.5 and 0.25; |log2| 1 and 2
    assert json.loads((tmp_path / "b.json").read_text())["dim"]["ratio"] == pytest.approx([0.5, 0.25], rel=1e-6)
    (res / "cases" / "photo-a" / "dim" / "probes_mirror.exr").unlink()
    with pytest.raises(SystemExit, match="probe renders are missing"):
        script.main([str(res), "--methods", "dim"])
    with pytest.raises(SystemExit, match="not a `roomlight bench run-photos` folder"):
        script.main([str(tmp_path / "no-such-run"), "--methods", "dim"])


def test_against_another_run_reports_the_levels_shift_and_how_the_photos_levels_agree(run, capsys, tmp_path):
    import shutil

    res, _ = run
    script = _script()
    brighter = tmp_path / "brighter"
    shutil.copytree(res, brighter)
    # photo a's light twice as bright (0.5 -> 1.0 of the truth), photo b's eight times (0.25 -> 2.0)
    for photo, factor in (("photo-a", 2.0), ("photo-b", 8.0)):
        for m in ("diffuse", "matte", "mirror"):
            path = brighter / "cases" / photo / "dim" / f"probes_{m}.exr"
            _write_rgb(path, factor * script._read_rgb(path))
    script.main([str(brighter), "--methods", "dim", "--against", str(res)])
    out = capsys.readouterr().out
    # shifts of +1 and +3 stops: mean +2; log2 levels (-1, -2) against (0, +1): anti-correlated
    assert "| dim | 2 | +2.00 | -1.00 |" in out
