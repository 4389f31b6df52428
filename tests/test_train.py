"""Tests of roomlight.prior.train: over-fitting, exact resumption, determinism, bad data, refusal of
incompatible resumes, non-finite losses, atomic checkpoints, schedule and config."""

from __future__ import annotations

import json
import math
import shutil

import click
import pytest
import torch
from click.testing import CliRunner

from roomlight.prior.data import write_toy_dataset
from roomlight.errors import RoomlightError
from roomlight.prior.eval.metrics import psnr, to_ldr
from roomlight.prior.model import PanoVAE
from roomlight.prior.model.families import ALL_PRESETS
from roomlight.prior.train import (TRAIN_PRESETS, Trainer, TrainConfig, TrainingError, config_differences,
                             get_train_preset, latest_checkpoint, learning_rate, resolve_run_model)
from roomlight.prior.train.checkpoint import optimizer_from_tensors, optimizer_to_tensors


pytestmark = pytest.mark.usefixtures("one_torch_thread")


FAST = dict(progress=False, log_every=1, val_every=0, ckpt_every=1000, image_every=0, num_workers=0)


def tiny(**overrides) -> TrainConfig:
    return get_train_preset("tiny").replace(**{**FAST, **overrides})


@pytest.fixture(scope="module")
def toy8(tmp_path_factory):
    root = tmp_path_factory.mktemp("toy8")
    write_toy_dataset(root, 8, 32)
    return root


def params(model) -> dict:
    return {k: v.detach().clone() for k, v in model.state_dict().items()}


def run(cfg, data, out, until=None) -> Trainer:
    t = Trainer(cfg, data, out, device="cpu", note=lambda m: None)
    t.fit(until)
    t.close()
    return t


def recon_psnr(model, ds) -> float:
    items = [ds[i] for i in range(len(ds))]
    rad = torch.stack([it["radiance"] for it in items])
    dep = torch.stack([it["depth"] for it in items])
    model.eval()
    with torch.no_grad():
        pr, _ = model.decode(model.encode(rad, dep).mean)
    return float(psnr(to_ldr(pr, rad), to_ldr(rad)).mean())


@pytest.mark.slow
def test_tiny_model_overfits_four_panoramas(tmp_path):
    data = tmp_path / "four"
    write_toy_dataset(data, 4, 32)
    cfg = tiny(max_steps=250, val_fraction=0.0, aug_roll=False, aug_mirror=False, aug_tilt_deg=0.0, cache=False,
               val_every=125)
    t = Trainer(cfg, data, tmp_path / "run", device="cpu", note=lambda m: None)
    before = recon_psnr(t.model, t.train_set)
    t.fit()
    t.close()
    after = recon_psnr(t.model, t.train_set)
    log = [json.loads(line) for line in (tmp_path / "run" / "log.jsonl").read_text().splitlines()]
    losses = [r["total"] for r in log if r["event"] == "train"]
    assert len(losses) == 250
    first, last = losses[0], sum(losses[-10:]) / 10
    assert first / last >= 5.0, (first, last)
    assert after > before + 3.0, (before, after)
    # The best model is a loadable PanoVAE with the training statistics inside.
    best = PanoVAE.from_pretrained(resolve_run_model(tmp_path / "run"))
    assert best.normalization == t.model.normalization
    assert best.metadata["training"]["max_steps"] == 250


def test_resume_equals_uninterrupted_run(toy8, tmp_path):
    cfg = tiny(max_steps=8, val_fraction=0.0)  # 2 batches per epoch; roll, mirror, tilt, sampling noise on
    straight = run(cfg, toy8, tmp_path / "straight")
    run(cfg, toy8, tmp_path / "resumed", until=4)
    assert latest_checkpoint(tmp_path / "resumed").name == "step-00000004"
    resumed = run(cfg, toy8, tmp_path / "resumed")
    assert resumed.step == 8
    a, b = params(straight.model), params(resumed.model)
    for k in a:
        torch.testing.assert_close(b[k], a[k], rtol=1e-6, atol=1e-7, msg=k)
    sa, sb = straight.optimizer.state_dict()["state"], resumed.optimizer.state_dict()["state"]
    for pid in sa:
        torch.testing.assert_close(sb[pid]["exp_avg_sq"], sa[pid]["exp_avg_sq"], rtol=1e-6, atol=1e-12)
    # The log reads like one run: steps 1..8, each once.
    steps = [json.loads(x)["step"] for x in (tmp_path / "resumed" / "log.jsonl").read_text().splitlines()
             if json.loads(x)["event"] == "train"]
    assert steps == list(range(1, 9))
    # Re-running a finished run does nothing.
    again = run(cfg, toy8, tmp_path / "resumed")
    assert again.step == 8


def test_time_budget_stops_with_a_checkpoint_and_the_run_continues_exactly(toy8, tmp_path):
    """A wall-clock budget (used to compare recipes at equal CPU cost) stops after the step that
    crosses it, checkpointed and validated, without changing the schedule."""
    cfg = tiny(max_steps=6, val_fraction=0.0)
    straight = run(cfg, toy8, tmp_path / "straight")
    t = Trainer(cfg, toy8, tmp_path / "budget", device="cpu", note=lambda m: None)
    summary = t.fit(time_budget_s=1e-9)  # already past after the first step
    t.close()
    assert summary["step"] == 1 and summary["total_steps"] == 6
    assert latest_checkpoint(tmp_path / "budget").name == "step-00000001"
    events = [json.loads(x)["event"] for x in (tmp_path / "budget" / "log.jsonl").read_text().splitlines()]
    assert "val_on_train" in events or "val" in events
    resumed = run(cfg, toy8, tmp_path / "budget")
    assert resumed.step == 6
    a, b = params(straight.model), params(resumed.model)
    for k in a:
        torch.testing.assert_close(b[k], a[k], rtol=1e-6, atol=1e-7, msg=k)


def test_same_seed_same_weights_other_seed_other_weights(toy8, tmp_path):
    cfg = tiny(max_steps=3, val_fraction=0.0)
    a = params(run(cfg, toy8, tmp_path / "a").model)
    b = params(run(cfg, toy8, tmp_path / "b").model)
    c = params(run(cfg.replace(seed=1), toy8, tmp_path / "c").model)
    assert all(torch.equal(a[k], b[k]) for k in a)
    assert not all(torch.equal(a[k], c[k]) for k in a)


def test_corrupt_file_is_skipped_by_name_during_training(toy8, tmp_path):
    data = tmp_path / "data"
    shutil.copytree(toy8, data, ignore=shutil.ignore_patterns(".*"))
    (data / "toy-00002.exr").write_bytes(b"\x76\x2f\x31\x01 truncated")  # EXR magic, then garbage
    notes = []
    for cache in (False, True):
        t = Trainer(tiny(max_steps=4, val_fraction=0.0, cache=cache), data, tmp_path / f"run{cache}",
                    device="cpu", note=notes.append)
        t.fit()
        t.close()
        assert t.step == 4
        log = [json.loads(x) for x in (tmp_path / f"run{cache}" / "log.jsonl").read_text().splitlines()]
        skipped = [r for r in log if r["event"] == "skipped"]
        if not cache:  # with the cache the file is reported once, when the cache is built
            assert [r["file"] for r in skipped] == ["toy-00002.exr"]
            assert "toy-00002.exr" in skipped[0]["reason"]
    assert any("skipping toy-00002.exr" in n for n in notes)


def test_incompatible_resume_is_refused_naming_the_fields(toy8, tmp_path):
    run(tiny(max_steps=2, val_fraction=0.0), toy8, tmp_path / "r")
    with pytest.raises(RoomlightError, match=r"differing fields: .*lr: 0\.002 -> 0\.001.*loss\.peak: 0\.1 -> 0\.0"):
        Trainer(tiny(max_steps=2, val_fraction=0.0, lr=1e-3, loss={"peak": 0.0}), toy8, tmp_path / "r", device="cpu")
    # Logging and checkpoint frequencies may change.
    t = Trainer(tiny(max_steps=2, val_fraction=0.0, log_every=7, ckpt_every=9), toy8, tmp_path / "r",
                device="cpu", note=lambda m: None)
    assert t.step == 2
    t.close()


def test_non_finite_loss_stops_with_step_files_and_last_checkpoint(toy8, tmp_path):
    cfg = tiny(max_steps=6, val_fraction=0.0, ckpt_every=2)
    t = Trainer(cfg, toy8, tmp_path / "r", device="cpu", note=lambda m: None)
    t.fit(until=2)
    with torch.no_grad():
        t.model.decoder.out_conv.conv.bias.fill_(float("nan"))
    with pytest.raises(TrainingError) as err:
        t.fit()
    msg = str(err.value)
    assert "non-finite loss at step 3" in msg
    assert "toy-000" in msg and "step-00000002" in msg
    t.close()
    assert json.loads((tmp_path / "r" / "log.jsonl").read_text().splitlines()[-1])["event"] == "stop"


def test_interrupted_save_leaves_previous_checkpoint_usable(toy8, tmp_path):
    run(tiny(max_steps=2, val_fraction=0.0), toy8, tmp_path / "r")
    ck = tmp_path / "r" / "checkpoints"
    # A kill during a save leaves a temporary directory, or a directory without its state file.
    (ck / ".tmp-step-00000003").mkdir()
    (ck / ".tmp-step-00000003" / "model.safetensors").write_bytes(b"partial")
    (ck / "step-00000009").mkdir()
    assert latest_checkpoint(tmp_path / "r").name == "step-00000002"
    t = run(tiny(max_steps=4, val_fraction=0.0).replace(max_steps=2), toy8, tmp_path / "r")
    assert t.step == 2


def test_optimizer_state_round_trips_through_safetensors():
    model = torch.nn.Linear(3, 2)
    opt = torch.optim.AdamW(model.parameters(), lr=1e-3, betas=(0.9, 0.99))
    model(torch.randn(4, 3)).sum().backward()
    opt.step()
    tensors, meta = optimizer_to_tensors(opt.state_dict())
    restored = optimizer_from_tensors(tensors, meta)
    opt2 = torch.optim.AdamW(torch.nn.Linear(3, 2).parameters(), lr=1.0)
    opt2.load_state_dict(restored)
    s1, s2 = opt.state_dict(), opt2.state_dict()
    assert s1["param_groups"] == s2["param_groups"]
    for pid in s1["state"]:
        for k in s1["state"][pid]:
            assert torch.equal(s1["state"][pid][k], s2["state"][pid][k])


def test_learning_rate_schedule():
    lrs = [learning_rate(s, 1000, 2e-4, 1e-5, 250) for s in range(1000)]
    assert lrs[0] == pytest.approx(2e-4 / 250)
    assert lrs[249] == pytest.approx(2e-4) and lrs[250] == pytest.approx(2e-4)
    assert all(a >= b for a, b in zip(lrs[250:], lrs[251:]))
    assert lrs[-1] == pytest.approx(1e-5, rel=1e-3)
    mid = 250 + 375
    assert lrs[mid] == pytest.approx(1e-5 + (2e-4 - 1e-5) * 0.5, rel=1e-6)  # cos(pi/2) = 0


def test_config_presets_serialisation_and_differences():
    for name, cfg in TRAIN_PRESETS.items():
        assert cfg.model_config == ALL_PRESETS[name]
        assert TrainConfig.from_dict(json.loads(json.dumps(cfg.to_dict()))) == cfg
    d = TRAIN_PRESETS["default"]
    assert (d.batch_size, d.lr, d.min_lr, d.warmup_steps, d.betas, d.weight_decay, d.grad_clip, d.epochs) == \
        (32, 2e-4, 1e-5, 250, (0.9, 0.99), 0.01, 10.0, 300)
    assert d.aug_tilt_deg == 7.0 and d.loss["kl_beta"] == 1e-3 and d.loss["kl_warmup_steps"] == 1000
    with pytest.raises(RoomlightError, match="unknown field"):
        TrainConfig.from_dict({"learning_rate": 1.0})
    with pytest.raises(RoomlightError, match="batch_size"):
        TrainConfig(batch_size=0)
    diffs = config_differences(d, d.replace(seed=3, num_workers=9, loss={"peak": 0.5}))
    assert diffs == ["loss.peak: 0.1 -> 0.5", "seed: 0 -> 3"]
    # Every field carries a doc comment (one line per field in the source).
    import inspect

    import roomlight.prior.train.config as mod

    src = inspect.getsource(mod.TrainConfig)
    for f in d.to_dict():
        assert "#: " in src.split(f"    {f}:")[0].rsplit("\n", 2)[-2], f


def test_train_cli_runs_resumes_and_refuses(toy8, tmp_path):
    from roomlight.cli import train as train_cli
    from roomlight.cli.common import RoomlightGroup

    @click.group(cls=RoomlightGroup)
    def cli():
        pass

    cli.add_command(train_cli.command)
    runner = CliRunner()
    args = ["train", "--data", str(toy8), "--out", str(tmp_path / "r"), "--config", "tiny", "--max-steps", "3",
            "--set", "progress=false", "--set", "val_fraction=0", "--set", "image_every=3"]
    res = runner.invoke(cli, args)
    assert res.exit_code == 0, res.output
    assert "trained to step 3/3" in res.output
    panel = tmp_path / "r" / "images" / "step-00000003.png"
    assert panel.stat().st_size > 500  # inputs above reconstructions, then samples
    res = runner.invoke(cli, args)
    assert res.exit_code == 0 and "nothing to do" in res.output
    res = runner.invoke(cli, args + ["--set", "loss.peak=0"])
    assert res.exit_code == 2 and "loss.peak" in res.output
    res = runner.invoke(cli, ["train", "--data", str(toy8), "--out", str(tmp_path / "p"), "--config", "tiny",
                              "--print-config", "--set", "aug_tilt_deg=0"])
    assert json.loads(res.output)["aug_tilt_deg"] == 0
    assert math.isfinite(json.loads((tmp_path / "r" / "best" / "best.json").read_text())["total"])


def test_init_from_starts_at_the_source_weights_and_statistics(toy8, tmp_path):
    """A run with ``init_from`` begins exactly at the source model (weights and normalisation,
    even when its own data would give other statistics), trains from there, and a model of
    another architecture is refused by name."""
    source_run = run(tiny(max_steps=3), toy8, tmp_path / "source")
    source = PanoVAE.from_pretrained(resolve_run_model(tmp_path / "source"))
    other = tmp_path / "other-data"
    write_toy_dataset(other, 6, 32, seed=5)  # different panoramas: different statistics
    t = Trainer(tiny(max_steps=2, init_from=str(tmp_path / "source")), other, tmp_path / "ft", device="cpu",
                note=lambda m: None)
    start = params(t.model)
    for k, v in params(source).items():
        assert torch.equal(start[k], v), k
    assert t.model.normalization.to_dict() == source.normalization.to_dict()
    fresh = Trainer(tiny(max_steps=2), other, tmp_path / "fresh", device="cpu", note=lambda m: None)
    assert fresh.model.normalization.to_dict() != source.normalization.to_dict()  # the adoption is visible
    fresh.close()
    t.fit()
    t.close()
    moved = max(float((params(t.model)[k] - v).abs().max()) for k, v in start.items() if v.is_floating_point())
    assert moved > 0
    assert source_run.step == 3
    with pytest.raises(RoomlightError, match="architecture differs"):
        Trainer(tiny(model="small", max_steps=2, init_from=str(tmp_path / "source")), other, tmp_path / "bad",
                device="cpu", note=lambda m: None)
