"""The prior that ships with roomlight: loadable, at the emitter resolution, and its samples show
light sources (a guard on the committed weights; the full quality figures are measured by
`roomlight eval-prior` and listed in docs/training.md)."""

from __future__ import annotations

import numpy as np
import pytest
import torch

pytestmark = pytest.mark.usefixtures("one_torch_thread")


@pytest.fixture(scope="module")
def bundled():
    from roomlight.demo import bundled_prior_path
    from roomlight.model import PanoVAE

    path = bundled_prior_path()
    assert path is not None, "the package must ship a prior in roomlight/assets/prior"
    return PanoVAE.from_pretrained(path).eval()


def test_bundled_prior_is_at_least_the_emitter_resolution_and_records_its_training(bundled):
    h, w = bundled.config.resolution
    assert h >= 64 and w == 2 * h
    training = bundled.metadata.get("training") or {}
    assert training.get("model") and training.get("max_steps")


def test_bundled_prior_samples_show_light_sources(bundled):
    """Brightest over median luminance of 64 samples (seed 0): real and procedural rooms have
    25-160x; a prior that lost its lights decodes ~2x. Targets: the median sample >= 20x and
    at least 75 % of the samples >= 10x."""
    z = torch.randn(64, bundled.config.latent_dim, generator=torch.Generator().manual_seed(0))
    with torch.no_grad():
        rad, depth = bundled.decode(z)
    # luminance by hand (Rec. 709), independent of the package's helpers
    y = (0.2126 * rad[:, 0] + 0.7152 * rad[:, 1] + 0.0722 * rad[:, 2]).flatten(1).double().numpy()
    contrast = y.max(1) / np.median(y, axis=1)
    assert np.median(contrast) >= 20.0, np.percentile(contrast, [10, 50, 90])
    assert np.mean(contrast >= 10.0) >= 0.75, np.percentile(contrast, [10, 25, 50])
    # plausible rooms: depth between 0.3 m and 40 m everywhere, finite radiance
    assert torch.isfinite(rad).all() and float(depth.min()) > 0.3 and float(depth.max()) < 40.0
