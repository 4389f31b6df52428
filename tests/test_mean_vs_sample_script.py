"""scripts/mean_vs_sample.py: its re-assembled VENI field is the model's own, and it reports every row."""

from __future__ import annotations

import pytest
import torch

from roomlight.prior.model.normalization import Normalization
from roomlight.prior.model.veni import VENI_PRESETS, VeniVAE

from helpers_scripts import load_script

pytestmark = pytest.mark.usefixtures("one_torch_thread")

NORM = Normalization(mean=(0.3, 0.3, 0.3, 1.0), std=(0.5, 0.5, 0.5, 0.4))


def _script():
    return load_script("mean_vs_sample")


def test_split_decoding_with_one_latent_is_the_models_decoding():
    torch.manual_seed(0)
    m = VeniVAE(VENI_PRESETS["veni-d-tiny"], NORM).double().eval()
    z = torch.randn(3, m.config.latent_dim, dtype=torch.float64)
    torch.testing.assert_close(_script()._veni_decode(m, z, z), m.decode_normalized(z), atol=1e-12, rtol=0)


def test_the_script_reports_mean_samples_and_the_split_row(tmp_path, capsys):
    from roomlight.prior.data import write_toy_dataset

    write_toy_dataset(tmp_path / "data", 6, height=16)
    torch.manual_seed(0)
    VeniVAE(VENI_PRESETS["veni-d-tiny"], NORM).save_pretrained(tmp_path / "m")
    assert _script().main([str(tmp_path / "m"), "--data", str(tmp_path / "data"), "--limit", "4",
                           "--samples", "2"]) == 0
    out = capsys.readouterr().out
    for row in ("| posterior mean |", "| posterior sample 1 |", "| posterior sample 2 |",
                "| mean, per-image inputs of sample 1 |"):
        assert row in out
