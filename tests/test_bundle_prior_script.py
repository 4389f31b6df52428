"""scripts/bundle_prior.py: replacing the bundled prior keeps the replaced weights' history, copies
the weights byte for byte and refuses what would silently change the product."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import pytest
import torch

from roomlight.prior.model import ModelConfig, Normalization, PanoVAE

from helpers_scripts import load_script

pytestmark = pytest.mark.usefixtures("one_torch_thread")

CFG = ModelConfig(resolution=(32, 64), latent_dim=8, ch=8, ch_mult=(1, 1, 2, 2), z_channels=4, norm_groups=4)


def _script():
    return load_script("bundle_prior")


def _model(seed: int, cfg: ModelConfig = CFG, metadata: dict | None = None) -> PanoVAE:
    torch.manual_seed(seed)
    m = PanoVAE(cfg, Normalization(mean=(0.5, 0.4, 0.3, 1.0), std=(0.7, 0.6, 0.5, 0.4)), metadata=metadata or {})
    with torch.no_grad():
        for p in m.parameters():
            p.add_(0.01 * torch.randn_like(p))
    return m


def _sha(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


@pytest.fixture
def bundle_and_run(tmp_path):
    dest = tmp_path / "assets" / "prior"
    _model(0, metadata={"data": "rooms A", "best_step": 100,
                        "earlier_schedules": [{"note": "first", "weights_sha256": "ab"}]}).save_pretrained(
        dest, training_config={"max_steps": 100, "loss": {"peak": 0.3}})
    run = tmp_path / "run"
    _model(1).save_pretrained(run / "best", training_config={"max_steps": 50, "init_from": str(dest)})
    (run / "best" / "best.json").write_text(json.dumps({"step": 40, "metric": "val/total", "value": 1.0}))
    return dest, run


def test_bundling_copies_the_weights_and_appends_the_replaced_ones_to_the_history(bundle_and_run, capsys):
    dest, run = bundle_and_run
    old_sha = _sha(dest / "model.safetensors")
    (dest / "view_encoder").mkdir()                 # trained for the weights being replaced
    (dest / "view_encoder" / "config.json").write_text("{}")
    assert _script().main([str(run), "--data", "rooms B", "--dest", str(dest)]) == 0
    assert "not carried over" in capsys.readouterr().out and not (dest / "view_encoder").exists()
    assert (dest / "model.safetensors").read_bytes() == (run / "best" / "model.safetensors").read_bytes()
    cfg = json.loads((dest / "config.json").read_text())
    meta = cfg["metadata"]
    assert meta["data"] == "rooms B" and meta["best_step"] == 40
    assert cfg["training"] == {"max_steps": 50, "init_from": str(dest)}
    assert [e.get("note") for e in meta["earlier_schedules"][:1]] == ["first"]
    replaced = meta["earlier_schedules"][1]
    assert replaced["weights_sha256"] == old_sha
    assert replaced["training"] == {"max_steps": 100, "loss": {"peak": 0.3}}
    assert replaced["data"] == "rooms A" and replaced["best_step"] == 100
    # the bundle loads (its checksum is verified on load) and decodes like the run's model
    z = torch.randn(2, CFG.latent_dim)
    with torch.no_grad():
        a = PanoVAE.from_pretrained(dest).eval().decode(z)
        b = PanoVAE.from_pretrained(run / "best").eval().decode(z)
    assert all(torch.equal(x, y) for x, y in zip(a, b))
    assert not any(p.name.startswith(".bundle-") or p.name.endswith(".replaced") for p in dest.parent.iterdir())
    assert dest.stat().st_mode & 0o755 == 0o755      # package data: readable by every user


def test_bundling_refuses_the_same_weights_and_another_architecture(bundle_and_run, tmp_path):
    dest, run = bundle_and_run
    before = (dest / "config.json").read_text()
    with pytest.raises(SystemExit, match="already holds"):
        _script().main([str(dest), "--data", "x", "--dest", str(dest)])
    other = tmp_path / "other"
    _model(2, ModelConfig(resolution=(32, 64), latent_dim=16, ch=8, ch_mult=(1, 1, 2, 2), z_channels=4,
                          norm_groups=4)).save_pretrained(other)
    with pytest.raises(SystemExit, match="another architecture"):
        _script().main([str(other), "--data", "x", "--dest", str(dest)])
    assert (dest / "config.json").read_text() == before
    assert _script().main([str(other), "--data", "x", "--dest", str(dest), "--allow-new-architecture"]) == 0
    assert json.loads((dest / "config.json").read_text())["model"]["latent_dim"] == 16


def test_bundling_ships_a_veni_model_and_refuses_to_replace_one_family_by_the_other(bundle_and_run, tmp_path):
    from roomlight.prior.model.bundled import BUNDLED_MODELS
    from roomlight.prior.model.families import load_model
    from roomlight.prior.model.veni import VENI_PRESETS, VeniVAE

    torch.manual_seed(3)
    veni = VeniVAE(VENI_PRESETS["veni-d-tiny"], Normalization(mean=(0.5, 0.4, 0.3, 1.0), std=(0.7, 0.6, 0.5, 0.4)))
    run = tmp_path / "veni-run"
    veni.save_pretrained(run / "best", training_config={"max_steps": 7})
    (run / "best" / "best.json").write_text(json.dumps({"step": 6, "metric": "val/total", "value": 2.0}))
    dest = tmp_path / "assets" / BUNDLED_MODELS["veni-d"]
    assert _script().main([str(run), "--data", "rooms C", "--dest", str(dest)]) == 0
    assert (dest / "model.safetensors").read_bytes() == (run / "best" / "model.safetensors").read_bytes()
    meta = json.loads((dest / "config.json").read_text())["metadata"]
    assert meta["data"] == "rooms C" and meta["best_step"] == 6 and meta["earlier_schedules"] == []
    shipped = load_model(dest)
    assert isinstance(shipped, VeniVAE)
    z = torch.randn(2, shipped.config.latent_dim)
    with torch.no_grad():
        assert all(torch.equal(a, b) for a, b in zip(shipped.eval().decode(z), veni.eval().decode(z)))
    prior_dest, _ = bundle_and_run           # a VENI model over the panoramic VAE's bundle: refused
    before = (prior_dest / "config.json").read_text()
    with pytest.raises(SystemExit, match="another architecture"):
        _script().main([str(run), "--data", "x", "--dest", str(prior_dest)])
    assert (prior_dest / "config.json").read_text() == before
