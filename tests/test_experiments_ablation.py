"""The ablation switches (AdaGN, latitude channels) and the ablation study's rows and run."""

import json

import pytest
import torch

from roomlight.errors import RoomlightError
from roomlight.evaluation.experiments.ablation import ABLATION_PRESETS, AblationConfig, row_train_config, run_ablation
from roomlight.evaluation.experiments.ablation_rows import ROWS
from roomlight.prior.model import ModelConfig, Normalization, PanoVAE, get_preset
from roomlight.prior.train.config import TrainConfig, config_differences, get_train_preset


def _params(model) -> int:
    return sum(p.numel() for p in model.parameters())


def _adagn_layers(cfg: ModelConfig) -> list[int]:
    """Channel count of every AdaGN of the decoder: two per residual block per stage, and the head."""
    chans = cfg.encoder_channels[::-1]
    return [chans[k + 1] for k in range(cfg.num_stages) for _ in range(2 * cfg.num_res_blocks)] + [chans[-1]]


@pytest.mark.parametrize("preset", ["tiny", "compact", "default"])
def test_switches_remove_exactly_their_parameters(preset):
    cfg = get_preset(preset)
    full = _params(PanoVAE(cfg))
    # AdaGN's Linear(latent, 2C) (weights and bias) becomes a GroupNorm's affine (2C)
    adagn = sum(cfg.latent_dim * 2 * c + 2 * c - 2 * c for c in _adagn_layers(cfg))
    assert full - _params(PanoVAE(cfg.override(adagn=False))) == adagn
    # two fewer input channels of the encoder stem (to ch) and of the decoder stem (to the widest stage)
    latitude = 2 * 9 * (cfg.ch + cfg.encoder_channels[-1])
    assert full - _params(PanoVAE(cfg.override(latitude=False))) == latitude
    assert full - _params(PanoVAE(cfg.override(adagn=False, latitude=False))) == adagn + latitude
    if preset == "default":
        assert full == 13_918_628  # the paper's network, both switches on


def test_without_adagn_the_latent_reaches_the_decoder_only_through_its_first_layer():
    torch.manual_seed(0)
    z = torch.randn(3, 16)
    for adagn, depends in ((False, False), (True, True)):
        model = PanoVAE(get_preset("tiny").override(adagn=adagn))
        with torch.no_grad():
            for p in model.decoder.parameters():  # every weight non-zero, AdaGN's linears included
                p.copy_(torch.randn_like(p) * 0.3)
            start = model.decoder.latent_to_map(z[:1]).expand(3, -1, -1, -1)
            out = model.decoder.decode_map(start, z)  # the same starting map for three latents
        differs = not torch.allclose(out[0], out[1]) or not torch.allclose(out[0], out[2])
        assert differs == depends


def test_without_latitude_channels_the_network_never_asks_for_them(monkeypatch):
    import roomlight.prior.model.networks as pv

    def refuse(*a, **k):
        raise AssertionError("latitude channels requested")

    monkeypatch.setattr(pv, "latitude_channels", refuse)
    x = torch.randn(2, 4, 16, 32)
    off = PanoVAE(get_preset("tiny").override(latitude=False))
    x_hat, _ = off(x)
    assert x_hat.shape == x.shape
    with pytest.raises(AssertionError, match="latitude"):
        PanoVAE(get_preset("tiny"))(x)


def _save(model, path):
    model.normalization = Normalization(mean=(0.5, 0.5, 0.5, 1.0), std=(1.0, 1.0, 1.0, 0.5))
    return model.save_pretrained(path)


def test_switches_are_saved_and_honoured_by_from_pretrained(tmp_path):
    torch.manual_seed(1)
    model = PanoVAE(get_preset("tiny").override(adagn=False, latitude=False))
    _save(model, tmp_path / "m")
    meta = json.loads((tmp_path / "m" / "config.json").read_text())
    assert meta["model"]["adagn"] is False and meta["model"]["latitude"] is False
    back = PanoVAE.from_pretrained(tmp_path / "m")
    assert back.config == model.config
    z = torch.randn(2, 16)
    with torch.no_grad():
        assert torch.equal(back.decode_normalized(z), model.eval().decode_normalized(z))


def test_config_files_without_the_switches_load_with_both_on(tmp_path):
    from roomlight.demo import bundled_prior_path

    _save(PanoVAE(get_preset("tiny")), tmp_path / "old")
    path = tmp_path / "old" / "config.json"
    meta = json.loads(path.read_text())
    del meta["model"]["adagn"], meta["model"]["latitude"]  # as written before the switches existed
    path.write_text(json.dumps(meta))
    model = PanoVAE.from_pretrained(tmp_path / "old")
    assert model.config.adagn and model.config.latitude
    bundled = PanoVAE.from_pretrained(bundled_prior_path())  # the paper's full model
    assert bundled.config.adagn and bundled.config.latitude


def test_train_config_model_overrides():
    cfg = get_train_preset("tiny").replace(model_overrides={"adagn": False})
    assert cfg.model_config.adagn is False and cfg.model_config.latitude is True
    merged = cfg.replace(model_overrides={"latitude": False})
    assert merged.model_config.adagn is False and merged.model_config.latitude is False
    with pytest.raises(RoomlightError, match="did you mean 'adagn'"):
        get_train_preset("tiny").replace(model_overrides={"adgn": False})
    saved = get_train_preset("tiny").to_dict()
    del saved["model_overrides"]  # a run folder written before the field existed
    assert TrainConfig.from_dict(saved).model_overrides == {}
    assert config_differences(get_train_preset("tiny"), cfg) == ["model_overrides.adagn: None -> False"]


def test_rows_share_one_budget_and_differ_only_in_their_switches():
    cfg = AblationConfig(preset="tiny", steps=40)
    configs = {row: row_train_config(cfg, row, progress=False) for row in ROWS}
    base = configs["full"]
    assert base.max_steps == 40 and base.model_config == get_preset("tiny")
    for row, tcfg in configs.items():
        loss, model = ROWS[row]
        for k in ("max_steps", "batch_size", "lr", "warmup_steps", "seed", "epochs", "aug_roll", "aug_tilt_deg"):
            assert getattr(tcfg, k) == getattr(base, k), (row, k)
        for k, v in tcfg.loss.items():
            assert v == loss.get(k, base.loss[k]), (row, k)
        assert tcfg.model_config == get_preset("tiny").override(**model)
    assert configs["none"].loss["peak"] == configs["none"].loss["grad_radiance"] == 0.0
    with pytest.raises(RoomlightError, match="unknown row"):
        AblationConfig(rows=("full", "no-kl"))


@pytest.mark.mitsuba
@pytest.mark.slow
def test_tiny_study_runs_every_row_and_resumes(tmp_path, one_torch_thread):
    cfg = ABLATION_PRESETS["tiny"]
    out = tmp_path / "study"
    notes = []
    summary = run_ablation(out, cfg, progress=False, note=notes.append)
    rows = summary["rows"]
    assert list(rows) == list(ROWS)
    tiny = get_preset("tiny")
    for row, rec in rows.items():
        _, model = ROWS[row]
        assert rec["training"]["steps"] == cfg.steps
        assert rec["training"]["parameters"] == _params(PanoVAE(tiny.override(**model)))
        for k in ("psnr_ldr", "ssim_ldr", "psnr_hdr", "abs_rel"):
            assert rec["latent"][k] == rec["latent"][k]  # finite, not NaN
        assert set(rec["matte"]) == {"psnr_ldr", "rmse_hdr", "angular_error"}
        saved = json.loads((out / "runs" / row / "best" / "config.json").read_text())["model"]
        assert (saved["adagn"], saved["latitude"]) == (model.get("adagn", True), model.get("latitude", True))
    md = (out / "ablation.md").read_text()
    assert md.count("\n| w/o") >= 5 and "Full model" in md
    assert (out / "figures" / "ablation.png").is_file() and (out / "figures" / "latent-fits.png").is_file()
    # a rerun trains and evaluates nothing
    stamps = {p: p.stat().st_mtime_ns for p in out.glob("runs/*/log.jsonl")}
    notes.clear()
    run_ablation(out, cfg, progress=False, note=notes.append)
    assert not any(n.startswith(("training row", "latent fits", "matte inverse")) for n in notes), notes
    assert stamps == {p: p.stat().st_mtime_ns for p in out.glob("runs/*/log.jsonl")}
    with pytest.raises(RoomlightError, match="other settings"):
        run_ablation(out, cfg.override(steps=31), progress=False, note=notes.append)
