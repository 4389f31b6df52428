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
    scores = script.case_scores(folder, script.changes([1.0, 0.7], [10.0]))
    inside = mask > 0
    level = float(radiance.mean())
    for m in script.MATERIALS:
        as_fitted = images[m] * level * (0.5 if m == "diffuse" else 1.0)
        assert scores["as fitted"]["level kept"][m] == pytest.approx(score_view(as_fitted, images[m], inside)["psnr_ldr"])
        # a contrast change is scaled back to the fitted diffuse mean: with this renderer, the same images
        for label in ("gamma 0.7", "blur 10°"):
            assert scores[label]["level kept"][m] == pytest.approx(scores["as fitted"]["level kept"][m], rel=1e-5)
    assert scores["as fitted"]["true level"]["diffuse"] > 90                     # exact: PSNR of a perfect render
    assert scores["as fitted"]["true level"]["mirror"] == pytest.approx(
        score_view(2.0 * images["mirror"], images["mirror"], inside)["psnr_ldr"], rel=1e-5)


def test_a_blur_keeps_a_uniform_light_and_the_energy_and_spreads_a_spot_by_its_width():
    """Against the obvious: a constant panorama is unchanged; the solid-angle-weighted energy of a random map, of
    a ring next to a pole and of a spot next to the other is kept; a point at the equator spreads over the
    asked angle (its standard deviation measured along the row and down the column)."""
    from roomlight.core.geometry.equirect import pixel_solid_angles

    script = load_script("light_contrast")
    h, w = 32, 64
    area = pixel_solid_angles(h, w).double().numpy()[..., None]
    flat = np.full((h, w, 3), 0.7, np.float32)
    assert script.blurred(flat, 10.0) == pytest.approx(flat, rel=1e-5)
    rng = np.random.default_rng(2)
    rad = rng.uniform(0, 1, (h, w, 3)).astype(np.float32)
    ring = np.zeros((h, w, 3), np.float32)
    ring[1] = 1.0
    spot = np.zeros((h, w, 3), np.float32)
    spot[h - 2, 40] = 1.0
    for image in (rad, ring, spot):
        energy = float((image * area).sum())
        assert float((script.blurred(image, 16.0) * area).sum()) == pytest.approx(energy, rel=0.01)
    centre = np.zeros((h, w, 3), np.float32)
    centre[h // 2, w // 2] = 1.0
    out = script.blurred(centre, 20.0)[..., 0]
    degrees_per_pixel = 180.0 / h
    along = out[h // 2] / out[h // 2].sum()
    down = out[:, w // 2] / out[:, w // 2].sum()
    x = (np.arange(w) - w // 2) * degrees_per_pixel
    y = (np.arange(h) - h // 2) * degrees_per_pixel
    assert np.sqrt((along * x ** 2).sum()) == pytest.approx(20.0, rel=0.05)
    assert np.sqrt((down * y ** 2).sum()) == pytest.approx(20.0, rel=0.05)
    assert script.blurred(rad, 0.0) == pytest.approx(rad)
