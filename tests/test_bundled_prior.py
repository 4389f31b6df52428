"""The priors that ship with roomlight (ours, and VENI / VENI+D when bundled): loadable, at the emitter
resolution, and their samples show light sources, judged against procedural training rooms rendered in the
test (a guard on the committed weights; the full quality figures are measured by `roomlight eval-prior` and
listed in docs/results.md)."""

from __future__ import annotations

import numpy as np
import pytest
import torch

pytestmark = pytest.mark.usefixtures("one_torch_thread")


@pytest.fixture(scope="module")
def bundled():
    from roomlight.demo import bundled_prior_path
    from roomlight.prior.model import PanoVAE

    path = bundled_prior_path()
    assert path is not None, "the package must ship a prior in roomlight/assets/prior"
    return PanoVAE.from_pretrained(path).eval()


def test_bundled_prior_is_at_least_the_emitter_resolution_and_records_its_training(bundled):
    h, w = bundled.config.resolution
    assert h >= 64 and w == 2 * h
    training = bundled.metadata.get("training") or {}
    assert training.get("model") and training.get("max_steps")


#: Per bundled model, recorded guards on top of the grounded check below: (least median brightest/median
#: luminance of 64 samples, least share of samples above 10x). Measured (seed 0): the lite prior 51x and
#: 94 %; the 512-latent prior 21x and 72 % (its shipping target was the median >= 20x; docs/results.md,
#: "The bundled prior"); VENI+D (latent 513) 16x and 59 %. VENI (latent 513, radiance only; 5.7x and 42 %:
#: most of its samples are rooms with soft light, a weakness recorded in docs/model.md) has none: its only
#: bound is the grounded one.
SAMPLE_CONTRAST_TARGETS = {
    "prior": (20.0, 0.70),
    "lite": (20.0, 0.75),
    "veni-d": (12.0, 0.50),
}
#: The procedural rooms rendered as the reference: the first four of the training split every bundled model
#: learnt from (data/rooms64b holds rooms 0-2399, of which the first 80 % are its training split).
REFERENCE_ROOMS = (0, 1, 2, 3)
#: The least share of samples that must show a light source (a flat prior shows none, the training rooms all).
LEAST_SHARE_WITH_LIGHT = 0.25


def _peak_contrast(y: np.ndarray) -> np.ndarray:
    """(B,) brightest over median of (B, N) luminances."""
    return y.max(1) / np.median(y, axis=1)


@pytest.fixture(scope="module")
def training_room_contrast():
    """Brightest over median luminance of the reference rooms, path-traced at the models' 64 x 128 from their
    capture points as `roomlight synth` renders them, with 4 samples a pixel instead of 144: the median is
    robust to the noise, and the brightest pixel sees a light source directly, which is noise-free."""
    from roomlight.datagen.synth.camera import render_aovs, render_radiance
    from roomlight.datagen.synth.rooms import generate_room
    from roomlight.datagen.synth.scene import build_scene

    out = []
    for seed in REFERENCE_ROOMS:
        room = generate_room(seed)
        scene = build_scene(room)
        rad = render_radiance(scene, room.capture, height=64, spp=4, seed=seed, yaw=room.yaw)
        _, _, emitter = render_aovs(scene, room.capture, height=64, spp=4, seed=seed, yaw=room.yaw)
        y = (0.2126 * rad[..., 0] + 0.7152 * rad[..., 1] + 0.0722 * rad[..., 2]).astype(np.float64).ravel()
        # what makes the contrast of a training room is a light source: its brightest pixel sees one
        assert emitter.ravel()[np.argmax(y)] > 0, f"room {seed}: the brightest pixel is no light source"
        out.append(float(_peak_contrast(y[None])[0]))
    return np.array(out)


@pytest.mark.mitsuba
@pytest.mark.parametrize("name", ["lite", "prior", "veni", "veni-d"])
def test_bundled_prior_samples_show_light_sources(name, training_room_contrast):
    """Brightest over median luminance of 64 samples (seed 0), against procedural training rooms rendered here.

    A sample shows a light source when its contrast is nearer, in log contrast, to that of a training room
    (the least contrasted of the reference rooms, whose brightest pixels are light sources) than to that of a
    room without one, a uniform panorama, whose contrast is exactly 1: contrast >= sqrt(least room contrast),
    5.7x today (the reference rooms measure 33-420x). At least a quarter of the samples must show one: a prior
    that lost its lights (a zero latent decodes 1.4-2x) shows none, the training rooms all do.
    """
    from roomlight.prior.model.bundled import bundled_model_path
    from roomlight.prior.model.runs import load_run_model

    if name.startswith("veni") and bundled_model_path(name) is None:
        pytest.skip(f"this checkout ships no bundled {name} model")
    bundled = load_run_model(name, device="cpu").eval()
    z = torch.randn(64, bundled.config.latent_dim, generator=torch.Generator().manual_seed(0))
    with torch.no_grad():
        rad, depth = bundled.decode(z)
    # luminance by hand (Rec. 709), independent of the package's helpers
    y = (0.2126 * rad[:, 0] + 0.7152 * rad[:, 1] + 0.0722 * rad[:, 2]).flatten(1).double().numpy()
    contrast = _peak_contrast(y)
    with_light = contrast >= np.sqrt(training_room_contrast.min())
    assert with_light.mean() >= LEAST_SHARE_WITH_LIGHT, (training_room_contrast, np.percentile(contrast, [25, 50, 75]))
    if name in SAMPLE_CONTRAST_TARGETS:
        least_median, least_share = SAMPLE_CONTRAST_TARGETS[name]
        assert np.median(contrast) >= least_median, np.percentile(contrast, [10, 50, 90])
        assert np.mean(contrast >= 10.0) >= least_share, np.percentile(contrast, [10, 25, 50])
    # plausible rooms: depth between 0.3 m and 40 m everywhere, finite radiance
    assert torch.isfinite(rad).all()
    if depth is not None:  # VENI decodes radiance only
        assert float(depth.min()) > 0.3 and float(depth.max()) < 40.0


@pytest.mark.parametrize("name", ["veni", "veni-d"])
def test_bundled_veni_models_match_the_bundled_prior_and_record_their_training(name):
    """The VENI rows of the tables are only comparable when the shipped models have the bundled prior's
    latent size and resolution and were trained on the same rooms."""
    import json

    from roomlight.demo import bundled_prior_path
    from roomlight.prior.model.bundled import bundled_model_path
    from roomlight.prior.model.runs import load_run_model
    from roomlight.prior.model.veni import VENI_FORMAT_VERSION

    path = bundled_model_path(name)
    if path is None:
        pytest.skip(f"this checkout ships no bundled {name} model")
    config = json.loads((path / "config.json").read_text())
    assert config["format"] == "roomlight.veni" and config["format_version"] == VENI_FORMAT_VERSION
    prior = json.loads((bundled_prior_path() / "config.json").read_text())
    veni = load_run_model(name, device="cpu")
    assert abs(veni.config.latent_dim - prior["model"]["latent_dim"]) <= 2  # 3 x 171 = 513 against 512
    assert list(veni.config.resolution) == list(prior["model"]["resolution"])
    assert veni.config.depth == (name == "veni-d")
    assert "rooms64b" in config["metadata"]["data"] and "rooms64b" in prior["metadata"]["data"]
