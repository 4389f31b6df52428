"""Growing a prior's latent (roomlight.prior.model.grow): the grown network computes what the trained one
computes, its new dimensions cost no KL, and training from it starts at the old network's loss."""

from __future__ import annotations

import pytest
import torch

from roomlight.prior.data import write_toy_dataset
from roomlight.errors import RoomlightError
from roomlight.prior.model import PRESETS, PanoVAE
from roomlight.prior.model.grow import can_grow, grow_latent_state
from roomlight.prior.train import Trainer, get_train_preset, resolve_run_model

pytestmark = pytest.mark.usefixtures("one_torch_thread")

FAST = dict(progress=False, log_every=1, val_every=0, ckpt_every=1000, image_every=0, num_workers=0)


def trained_tiny(seed: int = 0) -> PanoVAE:
    """A tiny network with every weight random (AdaGN's zero init would hide a wrong column copy)."""
    torch.manual_seed(seed)
    model = PanoVAE(PRESETS["tiny"])
    with torch.no_grad():
        for p in model.parameters():
            p.copy_(torch.randn_like(p) * 0.2)
    return model.eval()


def grown(model: PanoVAE, latent: int) -> PanoVAE:
    cfg = model.config.override(latent_dim=latent)
    big = PanoVAE(cfg, model.normalization).eval()
    big.load_state_dict(grow_latent_state(model.state_dict(), model.config, cfg,
                                          generator=torch.Generator().manual_seed(1)))
    return big


def test_grown_decoder_ignores_the_new_dimensions_and_matches_the_old():
    small = trained_tiny()
    big = grown(small, 40)
    z = torch.randn(3, small.config.latent_dim)
    extra = torch.randn(3, 40 - small.config.latent_dim) * 5.0  # whatever the new dimensions hold
    with torch.no_grad():
        ref = small.decoder(z)
        out = big.decoder(torch.cat([z, extra], 1))
    torch.testing.assert_close(out, ref, rtol=0, atol=1e-5)


def test_grown_encoder_keeps_the_old_posterior_and_the_new_dimensions_sit_at_the_prior():
    small = trained_tiny()
    big = grown(small, 40)
    x = torch.randn(2, 4, *small.config.resolution)
    d = small.config.latent_dim
    with torch.no_grad():
        m_small, m_big = small.encoder(x), big.encoder(x)
    torch.testing.assert_close(m_big[:, :d], m_small[:, :d], rtol=0, atol=1e-5)        # means
    torch.testing.assert_close(m_big[:, 40:40 + d], m_small[:, d:], rtol=0, atol=1e-5)  # log-variances
    new_mean, new_logvar = m_big[:, d:40], m_big[:, 40 + d:]
    assert float(new_logvar.abs().max()) == 0.0  # variance 1: the prior's
    # small but not zero: the new dimensions see the input from the first step
    assert 0 < float(new_mean.abs().max()) < 0.05 * float(m_small[:, :d].abs().max())
    # so their KL term is ~0 (0.5 (mu^2 + var - 1 - log var) with var = 1)
    assert float(0.5 * new_mean.square().sum(1).max()) < 1e-2


def test_only_a_larger_latent_may_grow():
    tiny = PRESETS["tiny"]
    assert can_grow(tiny, tiny.override(latent_dim=64))
    assert can_grow(tiny, tiny)
    assert not can_grow(tiny, tiny.override(latent_dim=8))
    assert not can_grow(tiny, tiny.override(latent_dim=64, ch=16))
    with pytest.raises(RoomlightError, match="only latent_dim may differ"):
        grow_latent_state(trained_tiny().state_dict(), tiny, tiny.override(ch=16))


def test_training_from_a_grown_latent_starts_at_the_source_loss(tmp_path):
    """``train --init-from RUN --set model_overrides.latent_dim=N`` begins where RUN ended: its first
    validation equals the source's to float precision (the new dimensions are ignored)."""
    data = tmp_path / "toy"
    write_toy_dataset(data, 8, 32)
    cfg = get_train_preset("tiny").replace(**FAST, max_steps=4)
    src = Trainer(cfg, data, tmp_path / "src", device="cpu", note=lambda m: None)
    src.fit()
    src.close()
    notes: list[str] = []
    big_cfg = cfg.replace(max_steps=2, init_from=str(tmp_path / "src"), model_overrides={"latent_dim": 48})
    big = Trainer(big_cfg, data, tmp_path / "big", device="cpu", note=notes.append)
    assert big.model.config.latent_dim == 48
    assert any("grew the latent from 16 to 48" in n for n in notes)
    source = PanoVAE.from_pretrained(resolve_run_model(tmp_path / "src"))
    items = [big.train_set[i] for i in range(4)]
    x_rad = torch.stack([it["radiance"] for it in items])
    x_dep = torch.stack([it["depth"] for it in items])
    with torch.no_grad():
        r_src, d_src = source.decode(source.encode(x_rad, x_dep).mean)
        r_big, d_big = big.model.decode(big.model.encode(x_rad, x_dep).mean)
    torch.testing.assert_close(r_big, r_src, rtol=1e-4, atol=1e-5)
    torch.testing.assert_close(d_big, d_src, rtol=1e-4, atol=1e-5)
    big.fit()
    big.close()
    with pytest.raises(RoomlightError, match="architecture differs"):
        Trainer(cfg.replace(init_from=str(tmp_path / "src"), model_overrides={"latent_dim": 8}), data,
                tmp_path / "shrunk", device="cpu", note=lambda m: None)


def test_a_grown_run_stopped_by_its_time_budget_resumes_bit_identically(tmp_path):
    """The long runs of a grown prior train in stretches (--time-budget, then the same command again):
    stopped after a stretch and resumed, a run ends with the weights of a run never stopped."""
    data = tmp_path / "toy"
    write_toy_dataset(data, 8, 32)
    base = get_train_preset("tiny").replace(**FAST, max_steps=3)
    src = Trainer(base, data, tmp_path / "src", device="cpu", note=lambda m: None)
    src.fit()
    src.close()
    cfg = base.replace(max_steps=6, init_from=str(tmp_path / "src"), model_overrides={"latent_dim": 24})
    straight = Trainer(cfg, data, tmp_path / "straight", device="cpu", note=lambda m: None)
    straight.fit()
    straight.close()
    first = Trainer(cfg, data, tmp_path / "stretches", device="cpu", note=lambda m: None)
    first.fit(time_budget_s=1e-9)  # stops after its first step, as a budget running out does
    first.close()
    assert first.step == 1
    again = Trainer(cfg, data, tmp_path / "stretches", device="cpu", note=lambda m: None)
    assert again.step == 1
    again.fit()
    again.close()
    a, b = straight.model.state_dict(), again.model.state_dict()
    for k in a:
        assert torch.equal(a[k], b[k]), k
