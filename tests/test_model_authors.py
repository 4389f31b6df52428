"""The paper authors' checkpoint format (roomlight.prior.model.convert): layout, loading, conversion.

The parity test compares the package against an independent functional forward written here
from the spec (docs/model.md, "The authors' run folder"), using only F.conv2d, F.group_norm and
explicit index-based spherical padding.
"""

from __future__ import annotations

import math

import pytest
import torch
import torch.nn.functional as F

from roomlight.errors import InputFileError
from roomlight.prior.model import (
    AUTHORS_NORMALIZATION,
    ModelConfig,
    PanoVAE,
    ThirdPartyCheckpointWarning,
    convert_authors_checkpoint,
    to_authors_state_dict,
)

pytestmark = pytest.mark.usefixtures("one_torch_thread")


# ----------------------------------------------------------------------------- size and layout
def test_default_parameter_count_and_authors_layout():
    model = PanoVAE()
    assert sum(p.numel() for p in model.parameters()) == 13_918_628
    assert len(list(model.buffers())) == 0
    theirs = to_authors_state_dict(model.state_dict(), model.config)
    expected = authors_layout()
    assert list(theirs) == list(expected)  # same keys, same order
    for key, shape in expected.items():
        assert tuple(theirs[key].shape) == shape, key
    assert sum(math.prod(s) for s in expected.values()) == 13_918_628
    assert len(expected) == 96


# ----------------------------------------------------------------------------- authors' format
def authors_layout() -> dict[str, tuple[int, ...]]:
    """The authors' state_dict keys and shapes, transcribed from the authors' published checkpoint (docs/model.md)."""
    E, D = "encoder.model.", "decoder.model."
    out: dict[str, tuple[int, ...]] = {}

    def conv(key, co, ci):
        out[key + ".weight"], out[key + ".bias"] = (co, ci, 3, 3), (co,)

    def res(idx, c, ada=False):  # state_dict order: norm1, norm2, conv1, conv2
        p = f"{D if ada else E}{idx}."
        for n in ("norm1", "norm2"):
            if ada:
                out[f"{p}{n}.to_scale_shift.weight"], out[f"{p}{n}.to_scale_shift.bias"] = \
                    (2 * c, 512), (2 * c,)
            else:
                out[f"{p}{n}.weight"], out[f"{p}{n}.bias"] = (c,), (c,)
        conv(f"{p}conv1.conv", c, c)
        conv(f"{p}conv2.conv", c, c)

    conv(f"{E}1.conv", 64, 6)
    for down, c_in, c in ((2, 64, 64), (4, 64, 128), (6, 128, 256), (8, 256, 256)):
        conv(f"{E}{down}.conv", c, c_in)
        res(down + 1, c)
    out[f"{E}10.weight"], out[f"{E}10.bias"] = (256,), (256,)
    conv(f"{E}12.conv", 32, 256)
    conv(f"{D}1.conv", 256, 34)
    for up, c_in, c in ((2, 256, 256), (4, 256, 128), (6, 128, 64), (8, 64, 64)):
        conv(f"{D}{up}.conv.conv", c, c_in)
        res(up + 1, c, ada=True)
    out[f"{D}10.to_scale_shift.weight"], out[f"{D}10.to_scale_shift.bias"] = (128, 512), (128,)
    conv(f"{D}12.conv", 4, 64)
    out["quant.weight"], out["quant.bias"] = (1024, 4096), (1024,)
    out["post_quant.weight"], out["post_quant.bias"] = (4096, 512), (4096,)
    return out


def random_authors_state_dict(seed: int = 0) -> dict[str, torch.Tensor]:
    g = torch.Generator().manual_seed(seed)
    sd = {}
    for key, shape in authors_layout().items():
        if len(shape) > 1:
            t = torch.randn(shape, generator=g) / math.sqrt(math.prod(shape[1:]))
            if "to_scale_shift" in key:
                t = t * 0.3
        elif "norm" in key and key.endswith("weight") or key == "encoder.model.10.weight":
            t = 1.0 + 0.1 * torch.randn(shape, generator=g)
        else:
            t = 0.1 * torch.randn(shape, generator=g)
        sd[key] = t
    return sd


def ref_spherical_pad(x: torch.Tensor) -> torch.Tensor:
    """One-pixel spherical padding by explicit indexing: padded(i, j) = x(row(i), col(i, j))."""
    _, _, h, w = x.shape
    i = torch.arange(-1, h + 1)
    j = torch.arange(-1, w + 1) % w
    beyond_pole = (i < 0) | (i >= h)
    row = torch.where(i < 0, -1 - i, torch.where(i >= h, 2 * h - 1 - i, i))
    col = torch.where(beyond_pole[:, None], (j[None, :] + w // 2) % w, j[None, :].expand(h + 2, -1))
    return x[:, :, row[:, None], col]


def ref_forward(sd: dict, x: torch.Tensor | None = None, z: torch.Tensor | None = None):
    """Direct functional forward of the authors' network (default config) from the spec."""
    E, D, G, eps = "encoder.model.", "decoder.model.", 8, 1e-6

    def lat(t):
        b, _, h, w = t.shape
        theta = (torch.arange(h, dtype=t.dtype) + 0.5) * math.pi / h
        c = torch.stack([torch.cos(theta), torch.sin(theta)])[None, :, :, None].expand(b, 2, h, w)
        return torch.cat([t, c], dim=1)

    def conv(t, key, stride=1):
        return F.conv2d(ref_spherical_pad(t), sd[key + ".weight"], sd[key + ".bias"], stride=stride)

    def gn(t, key):
        return F.group_norm(t, G, sd[key + ".weight"], sd[key + ".bias"], eps=eps)

    def ada(t, key, zz):
        c = t.shape[1]
        ss = F.linear(zz, sd[key + ".to_scale_shift.weight"], sd[key + ".to_scale_shift.bias"])
        return F.group_norm(t, G, eps=eps) * (1 + ss[:, :c, None, None]) + ss[:, c:, None, None]

    out = {}
    if x is not None:
        h = conv(lat(x), f"{E}1.conv")
        for down, res in ((2, 3), (4, 5), (6, 7), (8, 9)):
            h = conv(h, f"{E}{down}.conv", stride=2)
            r = conv(F.silu(gn(h, f"{E}{res}.norm1")), f"{E}{res}.conv1.conv")
            h = h + conv(F.silu(gn(r, f"{E}{res}.norm2")), f"{E}{res}.conv2.conv")
        h = conv(F.silu(gn(h, f"{E}10")), f"{E}12.conv")
        assert h.shape[1:] == (32, 8, 16)
        moments = F.linear(h.reshape(h.shape[0], -1), sd["quant.weight"], sd["quant.bias"])
        out["mean"], out["logvar"] = moments[:, :512], moments[:, 512:].clamp(-30, 20)
    if z is not None:
        h = F.linear(z, sd["post_quant.weight"], sd["post_quant.bias"]).reshape(-1, 32, 8, 16)
        h = conv(lat(h), f"{D}1.conv")
        for up, res in ((2, 3), (4, 5), (6, 7), (8, 9)):
            h = h.repeat_interleave(2, dim=2).repeat_interleave(2, dim=3)
            h = conv(h, f"{D}{up}.conv.conv")
            r = conv(F.silu(ada(h, f"{D}{res}.norm1", z)), f"{D}{res}.conv1.conv")
            h = h + conv(F.silu(ada(r, f"{D}{res}.norm2", z)), f"{D}{res}.conv2.conv")
        out["x_hat"] = conv(F.silu(ada(h, f"{D}10", z)), f"{D}12.conv")
    return out


AUTHORS_YAML = """\
model:
  resolution:
  - 128
  - 256
  latent_dim: 512
  ch: 64
  ch_mult:
  - 1
  - 2
  - 4
  - 4
  num_res_blocks: 1
  z_channels: 32
  norm_groups: 8
train:
  batch_size: 32
  lr: 0.0002
  epochs: 300
data_dir: /data/laval
"""


def _write_authors_run(directory, payload):
    directory.mkdir(parents=True, exist_ok=True)
    (directory / "config.yaml").write_text(AUTHORS_YAML)
    torch.save(payload, directory / "last_epoch.pth")
    return directory


@pytest.mark.slow
def test_from_pretrained_authors_run_matches_reference_forward(tmp_path):
    sd = random_authors_state_dict()
    run = _write_authors_run(tmp_path / "run", {"epoch": 299, "step": 21000, "state_dict": sd})
    with pytest.warns(ThirdPartyCheckpointWarning, match="pickle written by a third party"):
        model = PanoVAE.from_pretrained(run)
    assert model.config == ModelConfig()
    assert model.normalization == AUTHORS_NORMALIZATION
    assert model.metadata["depth_units"] == "scale-free"
    assert model.metadata["epoch"] == 299 and model.metadata["step"] == 21000
    assert model.metadata["training"]["batch_size"] == 32

    model = model.double()
    sd64 = {k: v.double() for k, v in sd.items()}
    g = torch.Generator().manual_seed(1)
    z = torch.randn(1, 512, generator=g, dtype=torch.float64)
    x = torch.randn(1, 4, 128, 256, generator=g, dtype=torch.float64)
    with torch.no_grad():
        ref = ref_forward(sd64, x=x, z=z)
        x_hat = model.decode_normalized(z)
        post = model.encode_normalized(x)
        radiance, depth = model.decode(z)
    assert ref["x_hat"].std() > 0.1  # the comparison is not between two near-constant maps
    torch.testing.assert_close(x_hat, ref["x_hat"], rtol=1e-9, atol=1e-9)
    torch.testing.assert_close(post.mean, ref["mean"], rtol=1e-9, atol=1e-9)
    torch.testing.assert_close(post.logvar, ref["logvar"], rtol=1e-9, atol=1e-9)
    # The authors' hard-coded normalisation and output mapping.
    mean = torch.tensor([0.9586, 0.7788, 0.4920, 0.0020], dtype=torch.float64).view(1, 4, 1, 1)
    std = torch.tensor([0.6250, 0.5933, 0.5579, 0.4601], dtype=torch.float64).view(1, 4, 1, 1)
    y = ref["x_hat"] * std + mean
    torch.testing.assert_close(radiance, torch.expm1(y[:, :3]).clamp(0, 1e6))
    torch.testing.assert_close(depth, torch.exp(y[:, 3:]))


def test_authors_bare_state_dict_and_conversion(tmp_path):
    sd = random_authors_state_dict(seed=3)
    run = _write_authors_run(tmp_path / "bare", sd)
    with pytest.warns(ThirdPartyCheckpointWarning):
        model = PanoVAE.from_pretrained(run / "last_epoch.pth")
    with pytest.warns(ThirdPartyCheckpointWarning):
        out = convert_authors_checkpoint(run, tmp_path / "converted")
    assert (out / "model.safetensors").exists() and not list(out.glob("*.pth"))
    converted = PanoVAE.from_pretrained(out)
    assert converted.metadata["depth_units"] == "scale-free"
    assert converted.normalization == AUTHORS_NORMALIZATION
    z = torch.randn(1, 512)
    with torch.no_grad():
        assert torch.equal(converted.decode_normalized(z), model.decode_normalized(z))
    # Back to the authors' layout: the very same tensors under the very same names.
    back = to_authors_state_dict(converted.state_dict(), converted.config)
    assert list(back) == list(sd) and all(torch.equal(back[k], sd[k]) for k in sd)


def test_authors_checkpoint_with_wrong_shapes_is_rejected(tmp_path):
    sd = random_authors_state_dict()
    sd["decoder.model.12.conv.weight"] = torch.zeros(3, 64, 3, 3)
    run = _write_authors_run(tmp_path / "bad", {"epoch": 0, "step": 0, "state_dict": sd})
    with pytest.warns(ThirdPartyCheckpointWarning), pytest.raises(
            InputFileError, match=r"decoder.out_conv.conv.weight: expected \(4, 64, 3, 3\)"):
        PanoVAE.from_pretrained(run)
