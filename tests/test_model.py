"""Tests of the prior's network, normalisation and checkpoint formats (roomlight.prior.model).

The authors' format has its own file, test_model_authors.py.
"""

from __future__ import annotations

import json
import math

import pytest
import torch
import torch.nn.functional as F

from roomlight.errors import InputFileError, RoomlightError, ShapeError
from roomlight.prior.model import DiagonalGaussian, ModelConfig, Normalization, PanoVAE, get_preset
from roomlight.prior.model.blocks import AdaGN, AdaGNResBlock, ResBlock, SphericalConv2d, Upsample
from test_model_authors import ref_spherical_pad

# A 4-stage config (like the paper's) that is cheap: downsampling factor 16, bottleneck 2 x 4.
FOUR_STAGE = ModelConfig(resolution=(32, 64), latent_dim=8, ch=8, ch_mult=(1, 1, 2, 2),
                         z_channels=4, norm_groups=4)


pytestmark = pytest.mark.usefixtures("one_torch_thread")
def _randomize(model: torch.nn.Module, seed: int = 0) -> torch.nn.Module:
    """Give every parameter (including the zero-initialised AdaGN linears) random values."""
    g = torch.Generator().manual_seed(seed)
    with torch.no_grad():
        for name, p in model.named_parameters():
            if p.dim() > 1:
                fan_in = p[0].numel()
                p.copy_(torch.randn(p.shape, generator=g) / math.sqrt(fan_in))
            elif "norm" in name and name.endswith("weight"):
                p.copy_(1.0 + 0.1 * torch.randn(p.shape, generator=g))
            else:
                p.copy_(0.1 * torch.randn(p.shape, generator=g))
    return model


def _tiny_norm() -> Normalization:
    return Normalization(mean=(0.5, 0.4, 0.3, 1.0), std=(0.7, 0.6, 0.5, 0.4))


# ----------------------------------------------------------------------------- config
def test_presets_are_valid_and_round_trip():
    for name in ("default", "small", "compact", "lite", "tiny"):
        cfg = get_preset(name)
        assert ModelConfig.from_dict(json.loads(json.dumps(cfg.to_dict()))) == cfg
    assert get_preset("default") == ModelConfig()


def test_config_rejects_bad_values():
    with pytest.raises(RoomlightError, match="norm_groups=3 does not divide"):
        ModelConfig(norm_groups=3)
    with pytest.raises(RoomlightError, match="W = 2 H"):
        ModelConfig(resolution=(128, 128))
    with pytest.raises(RoomlightError, match="not divisible by the downsampling factor 16"):
        ModelConfig(resolution=(120, 240))
    with pytest.raises(RoomlightError, match="unknown field"):
        ModelConfig.from_dict({"chanels": 3})
    with pytest.raises(RoomlightError, match="unknown model preset"):
        get_preset("huge")


def test_shapes_tiny():
    cfg = get_preset("tiny")
    model = PanoVAE(cfg, _tiny_norm()).eval()
    h, w = cfg.resolution
    x = torch.randn(2, 4, h, w)
    x_hat, post = model.forward_normalized(x)
    assert x_hat.shape == (2, 4, h, w)
    assert post.mean.shape == post.logvar.shape == (2, cfg.latent_dim)
    maps = model.encoder.feature_maps(x)
    assert [tuple(m.shape[-2:]) for m in maps] == [(16, 32), (8, 16), (4, 8), (4, 8)]
    radiance, depth = model.decode(torch.randn(3, cfg.latent_dim))
    assert radiance.shape == (3, 3, h, w) and depth.shape == (3, 1, h, w)
    assert radiance.min() >= 0 and depth.min() > 0
    post = model.encode(torch.rand(2, 3, h, w) * 5, torch.rand(2, 1, h, w) + 0.5)
    assert post.mode().shape == (2, cfg.latent_dim)


def test_inference_runs_sample_by_sample_with_the_batch_result():
    # Without autograd the CPU encode/decode loop over samples (faster there); the result must
    # be the whole-batch computation, and with gradients the batch still runs whole.
    model = _randomize(PanoVAE(get_preset("tiny"), _tiny_norm()), seed=3).eval()
    h, w = model.config.resolution
    z = torch.randn(4, model.config.latent_dim)
    x = torch.randn(4, 4, h, w)
    whole_dec, whole_enc = model.decoder(z), model.encoder(x)  # grad mode: one batched call
    calls = []
    hook = model.decoder.register_forward_pre_hook(lambda mod, args: calls.append(args[0].shape[0]))
    with torch.no_grad():
        torch.testing.assert_close(model.decode_normalized(z), whole_dec, rtol=1e-5, atol=1e-5)
        post = model.encode_normalized(x)
    assert calls == [1, 1, 1, 1]
    mean, logvar = whole_enc.chunk(2, dim=1)
    torch.testing.assert_close(post.mean, mean, rtol=1e-5, atol=1e-5)
    calls.clear()
    zg = z.clone().requires_grad_(True)
    model.decode_normalized(zg).sum().backward()
    hook.remove()
    assert calls == [4] and zg.grad is not None and zg.grad.abs().sum() > 0


def test_bad_inputs_raise_helpful_errors():
    model = PanoVAE(get_preset("tiny"))
    with pytest.raises(ShapeError, match=r"expected shape \(B, 4, 16, 32\), got \(1, 4, 32, 64\)"):
        model.encode_normalized(torch.zeros(1, 4, 32, 64))
    with pytest.raises(ShapeError, match=r"expected z of shape \(B, 16\)"):
        model.decode_normalized(torch.zeros(1, 15))
    with pytest.raises(RoomlightError, match="no normalisation statistics"):
        model.decode(torch.zeros(1, 16))
    model.normalization = _tiny_norm()
    with pytest.raises(RoomlightError, match="depth must be finite and > 0"):
        model.encode(torch.ones(1, 3, 16, 32), torch.zeros(1, 1, 16, 32))


def test_logvar_is_clamped():
    model = PanoVAE(get_preset("tiny"))
    with torch.no_grad():
        model.encoder.to_moments.bias[16:] = 100.0
    post = model.encode_normalized(torch.zeros(1, 4, 16, 32))
    assert torch.all(post.logvar == 20.0)


# ----------------------------------------------------------------------------- blocks
def test_adagn_zero_init_equals_groupnorm():
    torch.manual_seed(0)
    ada = AdaGN(16, 10, 4)
    x, z = torch.randn(3, 16, 4, 8) * 3 + 1, torch.randn(3, 10)
    assert torch.equal(ada.to_scale_shift.weight, torch.zeros(32, 10))
    torch.testing.assert_close(ada(x, z), F.group_norm(x, 4, eps=1e-6))
    # A fresh AdaGN ResBlock therefore equals a ResBlock with unit/zero GroupNorm affines.
    block, plain = AdaGNResBlock(16, 10, 4), ResBlock(16, 4)
    plain.conv1.load_state_dict(block.conv1.state_dict())
    plain.conv2.load_state_dict(block.conv2.state_dict())
    torch.testing.assert_close(block(x, z), plain(x))


def test_adagn_applies_scale_then_shift():
    ada = AdaGN(4, 2, 2)
    with torch.no_grad():
        ada.to_scale_shift.bias.copy_(torch.tensor([1.0, 2.0, 3.0, 4.0, 10.0, 20.0, 30.0, 40.0]))
    x = torch.randn(1, 4, 2, 4)
    ref = F.group_norm(x, 2, eps=1e-6) * torch.tensor([2.0, 3.0, 4.0, 5.0]).view(1, 4, 1, 1) \
        + torch.tensor([10.0, 20.0, 30.0, 40.0]).view(1, 4, 1, 1)
    torch.testing.assert_close(ada(x, torch.zeros(1, 2)), ref)


def test_adagn_batch_with_random_weights_matches_per_sample_formula():
    # AdaGN folds the per-sample affine into one GroupNorm over (1, B C, H, W); check it
    # against normalising each sample on its own by hand (mean/var over each group).
    torch.manual_seed(0)
    ada = AdaGN(8, 5, 4).double()
    with torch.no_grad():
        ada.to_scale_shift.weight.normal_()
        ada.to_scale_shift.bias.normal_()
    x, z = torch.randn(3, 8, 4, 6, dtype=torch.float64) * 2 + 1, torch.randn(3, 5, dtype=torch.float64)
    ss = z @ ada.to_scale_shift.weight.T + ada.to_scale_shift.bias
    ref = torch.empty_like(x)
    for b in range(3):
        for g in range(4):
            block = x[b, 2 * g:2 * g + 2]
            normed = (block - block.mean()) / torch.sqrt(block.var(unbiased=False) + 1e-6)
            for k in range(2):
                c = 2 * g + k
                ref[b, c] = normed[k] * (1 + ss[b, c]) + ss[b, 8 + c]
    torch.testing.assert_close(ada(x, z), ref)


@pytest.mark.parametrize("stride", [1, 2])
def test_padded_conv_matches_reference_and_is_roll_equivariant(stride):
    torch.manual_seed(0)
    conv = SphericalConv2d(3, 5, stride=stride).double()
    x = torch.randn(2, 3, 8, 16, dtype=torch.float64)
    ref = F.conv2d(ref_spherical_pad(x), conv.conv.weight, conv.conv.bias, stride=stride)
    torch.testing.assert_close(conv(x), ref)
    for k in (2, 6, 10):
        y = conv(torch.roll(x, k, dims=3))
        torch.testing.assert_close(y, torch.roll(conv(x), k // stride, dims=3), rtol=0, atol=1e-12)


def test_upsample_is_nearest_then_conv():
    """The phase-decomposed forward equals the definition (repeat, spherical pad, 3x3 conv) in
    value and in gradients w.r.t. input, weight and bias; odd widths take the literal path."""
    torch.manual_seed(0)
    up = Upsample(3, 5).double()
    for shape in ((1, 3, 4, 8), (2, 3, 6, 12), (2, 3, 3, 5)):
        x = torch.randn(*shape, dtype=torch.float64, requires_grad=True)
        big = x.repeat_interleave(2, dim=2).repeat_interleave(2, dim=3)
        ref = F.conv2d(ref_spherical_pad(big), up.conv.conv.weight, up.conv.conv.bias)
        out = up(x)
        torch.testing.assert_close(out, ref)
        g = torch.randn_like(ref)
        got = torch.autograd.grad(out, (x, up.conv.conv.weight, up.conv.conv.bias), g)
        want = torch.autograd.grad(ref, (x, up.conv.conv.weight, up.conv.conv.bias), g)
        for a, b in zip(got, want):
            torch.testing.assert_close(a, b)


def test_encoder_feature_maps_and_decoder_are_roll_equivariant():
    torch.manual_seed(0)
    model = _randomize(PanoVAE(FOUR_STAGE)).double().eval()
    f = FOUR_STAGE.downsample_factor
    assert f == 16
    x = torch.randn(2, 4, 32, 64, dtype=torch.float64)
    for k in (1, 3):
        shifted = model.encoder.feature_maps(torch.roll(x, k * f, dims=3))
        for level, (a, b) in enumerate(zip(model.encoder.feature_maps(x), shifted)):
            step = k * f * a.shape[-1] // 64
            torch.testing.assert_close(b, torch.roll(a, step, dims=3), rtol=0, atol=1e-10,
                                       msg=f"feature map {level}")
    z = torch.randn(2, FOUR_STAGE.latent_dim, dtype=torch.float64)
    h = model.decoder.latent_to_map(z)
    out = model.decoder.decode_map(h, z)
    out_rolled = model.decoder.decode_map(torch.roll(h, 1, dims=3), z)
    torch.testing.assert_close(out_rolled, torch.roll(out, f, dims=3), rtol=0, atol=1e-10)


# ----------------------------------------------------------------------------- determinism
def test_determinism_under_seed():
    cfg = get_preset("tiny")
    torch.manual_seed(123)
    a = PanoVAE(cfg)
    torch.manual_seed(123)
    b = PanoVAE(cfg)
    for (ka, va), (kb, vb) in zip(a.state_dict().items(), b.state_dict().items()):
        assert ka == kb and torch.equal(va, vb)
    x = torch.randn(2, 4, 16, 32)
    out1, _ = a.forward_normalized(x, sample=True, generator=torch.Generator().manual_seed(7))
    out2, _ = b.forward_normalized(x, sample=True, generator=torch.Generator().manual_seed(7))
    out3, _ = b.forward_normalized(x, sample=True, generator=torch.Generator().manual_seed(8))
    assert torch.equal(out1, out2)
    assert not torch.equal(out1, out3)
    # Eval mode defaults to the posterior mean, hence is deterministic without a generator.
    a.eval()
    assert torch.equal(a(x)[0], a(x)[0])


def test_posterior_sample_and_kl():
    mean = torch.tensor([[1.0, 0.0]])
    logvar = torch.log(torch.tensor([[4.0, 0.25]]))
    post = DiagonalGaussian(mean, logvar)
    expected = 0.5 * ((1 + 4 - 1 - math.log(4)) + (0 + 0.25 - 1 - math.log(0.25)))
    torch.testing.assert_close(post.kl(), torch.tensor([expected]))
    s = DiagonalGaussian(mean.expand(20000, 2), logvar.expand(20000, 2)).sample(
        torch.Generator().manual_seed(0))
    torch.testing.assert_close(s.mean(0), mean[0], atol=0.05, rtol=0)
    torch.testing.assert_close(s.std(0), torch.tensor([2.0, 0.5]), atol=0.05, rtol=0)


# ----------------------------------------------------------------------------- normalisation
def test_normalization_from_data_streams_exactly():
    g = torch.Generator().manual_seed(0)
    items = [(torch.rand(3, 4, 8, generator=g) * 20, torch.rand(1, 4, 8, generator=g) * 5 + 0.1)
             for _ in range(5)]
    batched = [(torch.stack([r for r, _ in items[:2]]), torch.stack([d for _, d in items[:2]]))]
    batched += [(r, d[0]) for r, d in items[2:]]  # mixed batching and (H, W) depth
    allx = torch.cat([torch.cat([torch.log1p(r.double()), torch.log(d.double())]).reshape(4, -1)
                      for r, d in items], dim=1)
    for source in (items, batched):
        norm = Normalization.from_data(iter(source))
        torch.testing.assert_close(torch.tensor(norm.mean, dtype=torch.float64), allx.mean(1))
        torch.testing.assert_close(torch.tensor(norm.std, dtype=torch.float64),
                                   allx.std(1, unbiased=False))
    assert Normalization.from_dict(json.loads(json.dumps(norm.to_dict()))) == norm
    with pytest.raises(RoomlightError, match="no data"):
        Normalization.from_data([])


def test_normalize_denormalize_round_trip():
    norm = _tiny_norm()
    radiance = torch.rand(2, 3, 4, 8, dtype=torch.float64) * 100
    depth = torch.rand(2, 1, 4, 8, dtype=torch.float64) * 10 + 0.1
    x = norm.normalize(radiance, depth)
    ref0 = (torch.log1p(radiance[:, 0]) - 0.5) / 0.7
    torch.testing.assert_close(x[:, 0], ref0)
    torch.testing.assert_close(x[:, 3], (torch.log(depth[:, 0]) - 1.0) / 0.4)
    r2, d2 = norm.denormalize(x)
    torch.testing.assert_close(r2, radiance)
    torch.testing.assert_close(d2, depth)
    huge, _ = norm.denormalize(torch.full((1, 4, 2, 4), 1000.0))
    assert huge.max() == 1e6  # clamped, not inf
    with pytest.raises(ShapeError, match="channels first"):
        norm.normalize(torch.rand(4, 8, 3), torch.rand(4, 8))


# ----------------------------------------------------------------------------- our checkpoints
def test_save_load_round_trip(tmp_path):
    torch.manual_seed(0)
    model = _randomize(PanoVAE(get_preset("tiny"), _tiny_norm())).eval()
    model.save_pretrained(tmp_path / "ckpt", training_config={"lr": 2e-4, "epochs": 3})
    meta = json.loads((tmp_path / "ckpt" / "config.json").read_text())
    assert meta["format"] == "roomlight.panovae" and meta["model"]["ch"] == 8
    assert meta["normalization"]["mean"] == list(_tiny_norm().mean)
    assert meta["training"] == {"lr": 2e-4, "epochs": 3} and "roomlight_version" in meta
    loaded = PanoVAE.from_pretrained(tmp_path / "ckpt")
    assert loaded.config == model.config and loaded.normalization == model.normalization
    assert loaded.metadata["depth_units"] == "metres"
    z = torch.randn(2, 16)
    x = torch.randn(2, 4, 16, 32)
    assert torch.equal(loaded.decode_normalized(z), model.decode_normalized(z))
    assert torch.equal(loaded.encode_normalized(x).mean, model.encode_normalized(x).mean)
    for a, b in zip(loaded.decode(z), model.decode(z)):
        assert torch.equal(a, b)
    # A file inside the folder works too.
    assert PanoVAE.from_pretrained(tmp_path / "ckpt" / "model.safetensors").config == model.config


def test_from_pretrained_errors(tmp_path):
    with pytest.raises(InputFileError, match="no such file"):
        PanoVAE.from_pretrained(tmp_path / "missing")
    with pytest.raises(InputFileError, match="not a checkpoint"):
        PanoVAE.from_pretrained(tmp_path)
    PanoVAE(get_preset("tiny"), _tiny_norm()).save_pretrained(tmp_path / "c")
    meta = json.loads((tmp_path / "c" / "config.json").read_text())
    meta["model"]["ch"] = 16
    (tmp_path / "c" / "config.json").write_text(json.dumps(meta))
    with pytest.raises(InputFileError, match="weights do not match the model config"):
        PanoVAE.from_pretrained(tmp_path / "c")
