"""scripts/light_contrast.py: the contrast change worked by hand, and the two levels it scores at checked on a
fitted light whose probe renders are stand-ins with known multiples of the truth."""

from __future__ import annotations

import json
from types import SimpleNamespace

import numpy as np
import pytest

from helpers_scripts import load_script


def test_a_contrast_change_raises_luminance_to_the_power_and_keeps_colour():
    script = load_script("light_contrast")
    rad = np.array([[[0.2, 0.4, 0.1], [4.0, 2.0, 1.0]], [[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]]], np.float32)
    y = 0.2126 * rad[..., 0] + 0.7152 * rad[..., 1] + 0.0722 * rad[..., 2]
    for gamma in (0.5, 1.0, 1.3):
        out = script.contrast_changed(rad, gamma)
        y_out = 0.2126 * out[..., 0] + 0.7152 * out[..., 1] + 0.0722 * out[..., 2]
        lit = y > 0
        assert y_out[lit] == pytest.approx(y[lit] ** gamma, rel=1e-5)
        # chromaticity: each texel is its input times one number
        assert out[0, 0] / rad[0, 0] == pytest.approx(np.full(3, (y[0, 0] ** gamma) / y[0, 0]), rel=1e-5)
        assert not out[1, 0].any()                   # black stays black, no division by zero
    assert script.contrast_changed(rad, 1.0) == pytest.approx(rad)


def test_scores_at_the_fitted_and_at_the_true_level(tmp_path, monkeypatch):
    """A stand-in renderer: every probe image is its truth times the light's mean radiance, the diffuse one times
    half of it as well. At the true level the diffuse probes are then exact and the mirror ones twice the truth;
    at the fitted level (gamma 1) the scores are the renders' own."""
    from roomlight.core.io import write_panorama
    from roomlight.evaluation.harness.metrics import score_view

    script = load_script("light_contrast")
    rng = np.random.default_rng(5)
    mask = np.zeros((6, 8), np.int32)
    mask[1:5, 2:7] = 1
    images = {m: rng.uniform(0.05, 0.4, (6, 8, 3)).astype(np.float32) for m in script.MATERIALS}
    truth = SimpleNamespace(window_mask=mask, probe_images=images)
    folder = tmp_path / "cases" / "photo-a" / "prior"
    folder.mkdir(parents=True)
    (folder / "result.json").write_text(json.dumps({"case_dir": "anywhere"}))
    radiance = rng.uniform(0.1, 3.0, (8, 16, 3)).astype(np.float32)
    write_panorama(folder / "recovered.exr", (radiance, np.full((8, 16), 2.0, np.float32)), half=False,
                   metadata={"emitter_kind": "mesh", "light_from_camera": np.eye(4).tolist()})

    def fake_score_light(truth_, light, spp, renders=None, given_depth=True):
        level = float(np.asarray(light.radiance).mean())
        for m in script.MATERIALS:
            renders[m] = images[m] * level * (0.5 if m == "diffuse" else 1.0)
        return {}

    monkeypatch.setattr("roomlight.evaluation.photobench.scoring.load_truth", lambda case_dir: truth)
    monkeypatch.setattr("roomlight.evaluation.photobench.scoring.score_light", fake_score_light)
    scores = script.case_scores(folder, [1.0, 0.7])
    inside = mask > 0
    level = float(radiance.mean())
    for m in script.MATERIALS:
        as_fitted = images[m] * level * (0.5 if m == "diffuse" else 1.0)
        assert scores[1.0]["level kept"][m] == pytest.approx(score_view(as_fitted, images[m], inside)["psnr_ldr"])
        # a contrast change is scaled back to the fitted diffuse mean: with this renderer, the same images
        assert scores[0.7]["level kept"][m] == pytest.approx(scores[1.0]["level kept"][m], rel=1e-5)
    assert scores[1.0]["true level"]["diffuse"] > 90                     # exact: PSNR of a perfect render
    assert scores[1.0]["true level"]["mirror"] == pytest.approx(
        score_view(2.0 * images["mirror"], images["mirror"], inside)["psnr_ldr"], rel=1e-5)
