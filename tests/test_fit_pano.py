"""Tests of latent fitting (roomlight.prior.latent_fit) and the fit-pano / convert commands."""

from __future__ import annotations

import json

import click
import pytest
import torch
from click.testing import CliRunner

from roomlight.prior.data import PanoramaDataset, find_panoramas, write_toy_dataset
from roomlight.errors import RoomlightError
from roomlight.prior.latent_fit import LatentFitConfig, fit_latent
from roomlight.core.io import read_panorama
from roomlight.prior.model import Normalization, PanoVAE, get_preset


pytestmark = pytest.mark.usefixtures("one_torch_thread")



@pytest.fixture(scope="module")
def toy(tmp_path_factory):
    """Three held-out toy panoramas (tensors at 16 x 32) and their folder."""
    root = tmp_path_factory.mktemp("toy")
    write_toy_dataset(root, 3, 32, seed=1000)
    ds = PanoramaDataset(find_panoramas(root), (16, 32), root=root)
    rad = torch.stack([ds[i]["radiance"] for i in range(3)])
    dep = torch.stack([ds[i]["depth"] for i in range(3)])
    return root, rad, dep


@pytest.fixture(scope="module")
def model(toy):
    """A tiny untrained prior whose AdaGN layers are given small random weights, so that z reaches
    every decoder layer (a fresh AdaGN is zero-initialised and ignores z)."""
    from roomlight.prior.model.blocks import AdaGN

    _, rad, dep = toy
    torch.manual_seed(0)
    m = PanoVAE(get_preset("tiny"), Normalization.from_data([(rad, dep)]))
    with torch.no_grad():
        for mod in m.modules():
            if isinstance(mod, AdaGN):
                for p in mod.parameters():
                    p.normal_(0.0, 0.05)
    return m.eval()


def objective(model, rad, dep, z, channels=(0, 1, 2, 3)):
    x = model.normalization.normalize(rad, dep)[:, list(channels)]
    with torch.no_grad():
        return (model.decode_normalized(z)[:, list(channels)] - x).pow(2).flatten(1).mean(1)


def test_fit_lowers_the_error_and_returns_the_best_iterate(model, toy):
    _, rad, dep = toy
    z0 = torch.zeros(3, model.config.latent_dim)
    start = objective(model, rad, dep, z0)
    res = fit_latent(model, rad, dep, LatentFitConfig(steps=60))
    assert res.z.shape == (3, model.config.latent_dim)
    assert torch.all(res.loss < start * 0.97), (start, res.loss)
    torch.testing.assert_close(res.loss, objective(model, rad, dep, res.z), rtol=1e-5, atol=1e-7)
    r, d = model.decode(res.z)
    torch.testing.assert_close(res.radiance, r)
    torch.testing.assert_close(res.depth, d)
    assert res.history[0][0] == 0 and res.history[-1][0] == 60
    assert res.history[-1][1] < res.history[0][1]
    # The weights are untouched and get their requires_grad back.
    assert all(p.requires_grad and p.grad is None for p in model.parameters())


def test_fit_recovers_a_panorama_the_decoder_can_express(model):
    z_true = torch.randn(2, model.config.latent_dim, generator=torch.Generator().manual_seed(5))
    with torch.no_grad():
        rad, dep = model.decode(z_true)
    start = objective(model, rad, dep, torch.zeros_like(z_true))
    res = fit_latent(model, rad, dep, LatentFitConfig(steps=300))
    assert torch.all(res.loss < start / 20), (start, res.loss)


def test_each_latent_is_fitted_independently_of_the_batch(model, toy):
    _, rad, dep = toy
    both = fit_latent(model, rad[:2], dep[:2], LatentFitConfig(steps=15))
    one = fit_latent(model, rad[1:2], dep[1:2], LatentFitConfig(steps=15))
    torch.testing.assert_close(both.z[1:2], one.z, rtol=1e-4, atol=1e-5)


def test_radiance_only_and_depth_only_targets(model, toy):
    _, rad, dep = toy
    r = fit_latent(model, rad, None, LatentFitConfig(steps=30, target="radiance"))
    z0 = torch.zeros(3, model.config.latent_dim)
    assert torch.all(r.loss < objective(model, rad, dep, z0, (0, 1, 2)))
    torch.testing.assert_close(r.loss, objective(model, rad, dep, r.z, (0, 1, 2)), rtol=1e-5, atol=1e-7)
    d = fit_latent(model, None, dep, LatentFitConfig(steps=30, target="depth"))
    assert torch.all(d.loss < objective(model, rad, dep, z0, (3,)))
    with pytest.raises(RoomlightError, match="needs depth"):
        fit_latent(model, rad, None, LatentFitConfig(target="both"))
    with pytest.raises(RoomlightError, match="target"):
        LatentFitConfig(target="rgb")


def test_learning_rate_decays_exponentially_to_the_final_value(model, toy, monkeypatch):
    _, rad, dep = toy
    seen = []
    orig = torch.optim.Adam.step

    def spy(self, *a, **k):
        seen.append(self.param_groups[0]["lr"])
        return orig(self, *a, **k)

    monkeypatch.setattr(torch.optim.Adam, "step", spy)
    fit_latent(model, rad[:1], dep[:1], LatentFitConfig(steps=10, lr=0.1, lr_final=0.01))
    assert seen[0] == pytest.approx(0.1)
    ratios = [b / a for a, b in zip(seen, seen[1:])]
    assert all(r == pytest.approx(0.1 ** 0.1) for r in ratios)
    assert seen[-1] * 0.1 ** 0.1 == pytest.approx(0.01)  # the rate after the last step


def _cli(*modules):
    from roomlight.cli.common import RoomlightGroup

    @click.group(cls=RoomlightGroup)
    def cli():
        pass

    for m in modules:
        cli.add_command(m.command)
    return cli


def test_fit_pano_cli_writes_a_better_fit(model, toy, tmp_path):
    from roomlight.cli import fit_pano

    root, rad, dep = toy
    model.save_pretrained(tmp_path / "m")
    pano = find_panoramas(root)[0]
    res = CliRunner().invoke(_cli(fit_pano), ["fit-pano", "--model", str(tmp_path / "m"), str(pano), "--steps", "40",
                                              "--out", str(tmp_path / "fit")])
    assert res.exit_code == 0, res.output
    rec = json.loads((tmp_path / "fit" / "latent.json").read_text())
    z0 = torch.zeros(1, model.config.latent_dim)
    assert rec["objective"] < float(objective(model, rad[:1], dep[:1], z0)[0])
    assert set(rec["metrics"]) == {"psnr_ldr", "ssim_ldr", "psnr_hdr", "peak_stops", "abs_rel"}
    fit = read_panorama(tmp_path / "fit" / "fit.exr")
    assert fit.radiance.shape == (16, 32, 3) and fit.depth.shape == (16, 32)
    for name in ("target.exr", "comparison.png", "emitter/emitter.ply", "emitter/scene.xml"):
        assert (tmp_path / "fit" / name).exists(), name
    # Radiance-only panoramas fall back to a radiance fit.
    from roomlight.core.io import write_panorama

    write_panorama(tmp_path / "rgb.exr", rad[0] * 2.0)
    res = CliRunner().invoke(_cli(fit_pano), ["fit-pano", "--model", str(tmp_path / "m"), str(tmp_path / "rgb.exr"),
                                              "--steps", "5", "--no-emitter"])
    assert res.exit_code == 0, res.output
    assert "(radiance, 5 steps)" in res.output
    res = CliRunner().invoke(_cli(fit_pano), ["fit-pano", "--model", str(tmp_path / "m"), str(tmp_path / "rgb.exr"),
                                              "--target", "both"])
    assert res.exit_code != 0 and "needs depth" in res.output
    res = CliRunner().invoke(_cli(fit_pano), ["fit-pano", "--model", str(tmp_path / "m"), str(tmp_path / "rgb.exr"),
                                              "--depth-weight", "3"])
    assert res.exit_code != 0 and "needs --target both" in res.output and "Traceback" not in res.output
    # The weighted objective from the encoder's mean: its settings are recorded, its objective is lower
    # than at the start.
    res = CliRunner().invoke(_cli(fit_pano), ["fit-pano", "--model", str(tmp_path / "m"), str(pano), "--steps", "10",
                                              "--init", "encoder", "--depth-weight", "3", "--peak-weight", "0.2",
                                              "--no-emitter", "--out", str(tmp_path / "wfit")])
    assert res.exit_code == 0, res.output
    rec = json.loads((tmp_path / "wfit" / "latent.json").read_text())
    assert rec["fit"]["depth_weight"] == 3 and rec["fit"]["peak_weight"] == 0.2 and rec["fit"]["init_from_encoder"]
    with torch.no_grad():
        z_enc = model.encode(rad[:1], dep[:1]).mean
    assert rec["objective"] <= float(_slow_weighted_objective(model, rad[:1], dep[:1], z_enc, 3.0, 0.2)[0]) + 1e-6


def test_convert_cli_writes_a_loadable_checkpoint(tmp_path):
    from roomlight.cli import convert
    from roomlight.prior.model import to_authors_state_dict

    cfg = get_preset("tiny")
    torch.manual_seed(1)
    src = PanoVAE(cfg)
    run = tmp_path / "authors"
    run.mkdir()
    torch.save({"epoch": 3, "step": 40, "state_dict": to_authors_state_dict(src.state_dict(), cfg)},
               run / "last_epoch.pth")
    (run / "config.yaml").write_text(
        "model:\n  resolution: [16, 32]\n  latent_dim: 16\n  ch: 8\n  ch_mult: [1, 2]\n  num_res_blocks: 1\n"
        "  z_channels: 4\n  norm_groups: 4\ntrain:\n  lr: 0.0002\n")
    res = CliRunner().invoke(_cli(convert), ["convert", str(run), str(tmp_path / "ours")])
    assert res.exit_code == 0, res.output
    assert "third party" in res.output
    m = PanoVAE.from_pretrained(tmp_path / "ours")
    assert m.metadata["depth_units"] == "scale-free"
    for k, v in src.state_dict().items():
        assert torch.equal(m.state_dict()[k], v)


def test_fit_latent_restores_each_parameters_requires_grad(model, toy):
    _, rad, dep = toy
    params = list(model.parameters())
    before = [p.requires_grad for p in params]
    params[0].requires_grad_(False)  # a partly frozen model comes back partly frozen
    flags = [p.requires_grad for p in params]
    try:
        fit_latent(model, rad[:1], dep[:1], LatentFitConfig(steps=2))
        assert [p.requires_grad for p in params] == flags
        assert all(p.grad is None for p in params)  # the decoder got no gradient
    finally:
        for p, flag in zip(params, before):
            p.requires_grad_(flag)


def test_latent_fit_config_is_strict_and_round_trips():
    cfg = LatentFitConfig(steps=7, target="radiance")
    assert LatentFitConfig.from_dict(cfg.to_dict()) == cfg
    assert cfg.override(lr=0.05).lr == 0.05
    with pytest.raises(RoomlightError, match="unknown field"):
        cfg.override(stpes=3)
    with pytest.raises(RoomlightError, match="unknown field"):
        LatentFitConfig.from_dict({"steps": 3, "learning_rate": 0.1})


def _slow_weighted_objective(model, rad, dep, z, depth_weight, peak_weight, fraction=0.005):
    """The weighted latent-fit objective written out pixel by pixel, one panorama at a time."""
    import math

    x = model.normalization.normalize(rad, dep)
    with torch.no_grad():
        x_hat = model.decode_normalized(z)
        pred, _ = model.normalization.denormalize(x_hat)
    out = []
    for i in range(rad.shape[0]):
        mse = [float((x_hat[i, c] - x[i, c]).pow(2).mean()) for c in range(4)]
        value = (mse[0] + mse[1] + mse[2] + depth_weight * mse[3]) / (3 + depth_weight)
        if peak_weight:
            h, w = rad.shape[-2:]
            k = max(1, math.ceil(fraction * h * w))

            def lum(img):
                return [0.2126 * float(img[0, p // w, p % w]) + 0.7152 * float(img[1, p // w, p % w])
                        + 0.0722 * float(img[2, p // w, p % w]) for p in range(h * w)]

            brightest = set()
            for img in (pred[i], rad[i].clamp_min(0.0)):
                values = lum(img)
                brightest |= set(sorted(range(h * w), key=lambda p: -values[p])[:k])
            err = [abs(math.log(float(pred[i, c, p // w, p % w]) + 1e-6)
                       - math.log(float(rad[i, c, p // w, p % w].clamp_min(0.0)) + 1e-6))
                   for p in brightest for c in range(3)]
            value += peak_weight * sum(err) / len(err)
        out.append(value)
    return torch.tensor(out)


def test_weighted_objective_matches_a_pixel_by_pixel_computation(model, toy):
    _, rad, dep = toy
    z = torch.randn(3, model.config.latent_dim, generator=torch.Generator().manual_seed(2)) * 0.5
    for depth_weight, peak_weight in ((1.0, 0.0), (3.0, 0.0), (3.0, 0.2), (0.5, 1.0)):
        cfg = LatentFitConfig(steps=0, depth_weight=depth_weight, peak_weight=peak_weight)
        res = fit_latent(model, rad, dep, cfg, z0=z)  # 0 steps: the objective at z
        expected = _slow_weighted_objective(model, rad, dep, z, depth_weight, peak_weight)
        torch.testing.assert_close(res.loss, expected.to(res.loss.dtype), rtol=1e-4, atol=1e-6)
    assert LatentFitConfig().is_paper_protocol and not LatentFitConfig(peak_weight=0.1).is_paper_protocol


def test_weighted_fit_lowers_its_objective_independently_of_the_batch(model, toy):
    _, rad, dep = toy
    cfg = LatentFitConfig(steps=25, depth_weight=3.0, peak_weight=0.2)
    z0 = torch.zeros(3, model.config.latent_dim)
    start = _slow_weighted_objective(model, rad, dep, z0, 3.0, 0.2)
    both = fit_latent(model, rad[:2], dep[:2], cfg)
    assert torch.all(both.loss < start[:2] - 0.02), (start, both.loss)
    torch.testing.assert_close(both.loss, _slow_weighted_objective(model, rad[:2], dep[:2], both.z, 3.0, 0.2),
                               rtol=1e-4, atol=1e-6)
    one = fit_latent(model, rad[1:2], dep[1:2], cfg)
    torch.testing.assert_close(both.z[1:2], one.z, rtol=1e-4, atol=1e-5)


def test_weighted_objective_settings_are_checked():
    with pytest.raises(RoomlightError, match="peak term needs radiance"):
        LatentFitConfig(target="depth", peak_weight=0.1)
    with pytest.raises(RoomlightError, match=">= 0"):
        LatentFitConfig(peak_weight=-1.0)
    with pytest.raises(RoomlightError, match="peak_fraction"):
        LatentFitConfig(peak_fraction=0.0)
