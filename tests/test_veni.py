"""VENI and VENI+D: the equivariant layers against slow references written from their equations,
exact equivariance of the encoder and the decoder to rolling the panorama, checkpoints, the fitting
methods and exact resumption of training."""

from __future__ import annotations

import math

import pytest
import torch

from roomlight.errors import RoomlightError
from roomlight.prior.model.equivariant import SO2Linear, VNAttention, VNBlock, VNLayerNorm, VNLinear, VNReLU, rotate_planar
from roomlight.prior.model.normalization import Normalization
from roomlight.prior.model.veni import VENI_PRESETS, VeniConfig, VeniField, VeniVAE, rotate_latent

NORM = Normalization(mean=(0.3, 0.3, 0.3, 1.0), std=(0.5, 0.5, 0.5, 0.4))


def model(name: str, seed: int = 0, dtype=torch.float64) -> VeniVAE:
    torch.manual_seed(seed)
    return VeniVAE(VENI_PRESETS[name], NORM).to(dtype).eval()


# ----------------------------------------------------------------------------- layers
def test_so2_linear_equals_its_equations_evaluated_in_loops():
    torch.manual_seed(1)
    c_in, inv_in, c_out, inv_out = 3, 2, 4, 2
    layer = SO2Linear(c_in, inv_in, c_out, inv_out).double()
    x = torch.randn(2, c_in, 2 + inv_in, dtype=torch.float64)
    with torch.no_grad():
        y = layer(x)
    A = layer.planar.detach()
    for b in range(2):
        t = [[1.0] + [float(x[b, i, 2 + k]) for k in range(inv_in)] for i in range(c_in)]
        for o in range(c_out):
            for v in range(2):  # planar out[o, v] = sum_i sum_k A[o, k, i] T[i, k] P[i, v]
                ref = sum(float(A[o, k, i]) * t[i][k] * float(x[b, i, v]) for i in range(c_in) for k in range(1 + inv_in))
                assert abs(float(y[b, o, v]) - ref) < 1e-12
        feats = []  # invariant out = B vec([Q, |P|]) + b, channel-major
        for i in range(c_in):
            feats += [float(x[b, i, 2 + k]) for k in range(inv_in)]
            feats.append(math.sqrt(float(x[b, i, 0]) ** 2 + float(x[b, i, 1]) ** 2 + 1e-6))
        for o in range(c_out):
            for k in range(inv_out):
                row = o * inv_out + k
                ref = sum(float(layer.invariant.weight.detach()[row, j]) * f for j, f in enumerate(feats))
                ref += float(layer.invariant.bias.detach()[row])
                assert abs(float(y[b, o, 2 + k]) - ref) < 1e-12


def test_vn_relu_is_the_projection_of_its_equation():
    torch.manual_seed(2)
    layer = VNReLU(3).double()
    x = torch.randn(5, 3, 4, dtype=torch.float64)
    with torch.no_grad():
        y = layer(x)
        q = torch.einsum("oi,nid->nod", layer.q.weight, x)
        k = torch.einsum("oi,nid->nod", layer.k.weight, x)
    for n in range(5):
        for c in range(3):
            kh = k[n, c] / math.sqrt(float(k[n, c].square().sum()) + 1e-6)
            dot = float(q[n, c] @ kh)
            ref = q[n, c] if dot >= 0 else q[n, c] - dot * kh
            assert torch.allclose(y[n, c], ref, atol=1e-12)


@pytest.mark.parametrize("angle", [0.3, math.pi / 2, 2.5])
def test_layers_commute_with_a_planar_rotation(angle):
    torch.manual_seed(3)
    x = torch.randn(2, 7, 6, 5, dtype=torch.float64)  # (B, tokens, channels, 2 + 3)
    layers = [SO2Linear(6, 3, 4, 3), VNLinear(6, 6), VNReLU(6), VNLayerNorm(6), VNBlock(6, 2)]
    for layer in layers:
        layer = layer.double()
        a = layer(rotate_planar(x, angle))
        b = rotate_planar(layer(x), angle)
        torch.testing.assert_close(a, b, atol=1e-10, rtol=1e-10, msg=type(layer).__name__)
    attn = VNAttention(6, 2).double()
    perm = torch.randperm(7)
    torch.testing.assert_close(attn(x[:, perm]), attn(x)[:, perm], atol=1e-10, rtol=1e-10)


def test_the_field_first_layer_equals_the_written_out_invariants():
    f = VeniField(VENI_PRESETS["veni-d-tiny"]).double()
    z = torch.randn(3, VENI_PRESETS["veni-d-tiny"].latent_dim, dtype=torch.float64)
    d = torch.nn.functional.normalize(torch.randn(50, 3, dtype=torch.float64), dim=-1)
    pixel, image = f.invariants(z, d)
    w = torch.cat([f.dot.weight, f.cross.weight, f.geo.weight], 1)
    ref = pixel @ w.T + f.geo.bias + (image @ f.cond[0].weight.T + f.cond[0].bias)[:, None]
    torch.testing.assert_close(f.first_layer(z, d), ref, atol=1e-12, rtol=1e-12)


def test_the_field_is_differentiable_at_the_origin_of_the_latent():
    """The posterior mean of a collapsed latent vector, and the fits' start z = 0, sit at the origin;
    a norm |Z_i⊥| among the field's inputs put a cusp there (one-sided slopes of opposite sign, a
    gradient of 0), which is what made the encoder's mean decode far worse than its samples. One-sided
    finite differences must agree with the autograd directional derivative."""
    f = VeniField(VENI_PRESETS["veni-d-tiny"]).double()
    torch.manual_seed(1)
    d = torch.nn.functional.normalize(torch.randn(40, 3, dtype=torch.float64), dim=-1)
    z0 = torch.zeros(1, VENI_PRESETS["veni-d-tiny"].latent_dim, dtype=torch.float64)
    v = torch.randn_like(z0)
    _, jv = torch.autograd.functional.jvp(lambda z: f(z, d), (z0,), (v,))
    eps = 1e-4
    for sign in (1.0, -1.0):
        one_sided = (f(z0 + sign * eps * v, d) - f(z0, d)) / (sign * eps)
        torch.testing.assert_close(one_sided, jv, atol=1e-3 * float(jv.abs().max()), rtol=0)


# ----------------------------------------------------------------------------- equivariance of the model
@pytest.mark.parametrize("name", ["veni-tiny", "veni-d-tiny"])
@pytest.mark.parametrize("k", [1, 5, 16])
def test_rolling_the_panorama_rotates_the_latent_and_rolling_back_the_decoding(name, k):
    m = model(name)
    h, w = m.config.resolution
    x = torch.randn(2, 4, h, w, dtype=torch.float64)
    angle = 2 * math.pi * k / w
    post, rolled = m.encode_normalized(x), m.encode_normalized(torch.roll(x, k, dims=3))
    # the planar parts (x, z) of every latent vector turn by 2 pi k / W, the heights y stay
    torch.testing.assert_close(rolled.mean, rotate_latent(post.mean, angle), atol=1e-6, rtol=1e-6)
    torch.testing.assert_close(rolled.logvar, post.logvar, atol=1e-6, rtol=1e-6)
    assert not torch.allclose(rolled.mean, post.mean, atol=1e-3)  # the latent does move
    z = torch.randn(2, m.config.latent_dim, dtype=torch.float64)
    torch.testing.assert_close(m.decode_normalized(rotate_latent(z, angle)),
                               torch.roll(m.decode_normalized(z), k, dims=3), atol=1e-6, rtol=1e-6)


def test_rotate_latent_turns_x_z_and_keeps_y():
    z = torch.tensor([1.0, 2.0, 0.0, 0.0, -1.0, 3.0])
    r = rotate_latent(z, math.pi / 2).reshape(2, 3)
    torch.testing.assert_close(r, torch.tensor([[0.0, 2.0, 1.0], [-3.0, -1.0, 0.0]]), atol=1e-7, rtol=0)


def test_veni_decodes_radiance_only_and_veni_d_radiance_and_depth():
    z = torch.randn(2, VENI_PRESETS["veni-tiny"].latent_dim, dtype=torch.float64)
    rad, depth = model("veni-tiny").decode(z)
    assert rad.shape == (2, 3, 16, 32) and depth is None and (rad >= 0).all()
    rad, depth = model("veni-d-tiny").decode(z)
    assert rad.shape == (2, 3, 16, 32) and depth.shape == (2, 1, 16, 32) and (depth > 0).all()
    x = torch.randn(2, 4, 16, 32, dtype=torch.float64)
    x_hat, _ = model("veni-tiny").forward_normalized(x, sample=False)
    assert torch.equal(x_hat[:, 3], x[:, 3])  # the depth channel is passed through: no depth loss for VENI


def test_config_validation_and_latent_size():
    assert VENI_PRESETS["veni"].latent_dim == 129 and VENI_PRESETS["veni"].in_channels == 3
    assert VENI_PRESETS["veni-d"].in_channels == 4
    from roomlight.errors import RoomlightError

    with pytest.raises(RoomlightError, match="W = 2 H"):
        VeniConfig(resolution=(16, 16))
    with pytest.raises(RoomlightError, match="heads"):
        VeniConfig(channels=10, heads=4)


def test_checkpoint_round_trip_through_the_common_loader(tmp_path):
    from roomlight.prior.model.runs import load_run_model

    m = model("veni-d-tiny", dtype=torch.float32)
    m.save_pretrained(tmp_path / "m", training_config={"note": "test"})
    back = load_run_model(tmp_path / "m", device="cpu")
    assert isinstance(back, VeniVAE) and back.config == m.config and back.normalization == NORM
    z = torch.randn(1, m.config.latent_dim)
    for a, b in zip(m.decode(z), back.decode(z)):
        assert torch.equal(a, b)
    import json

    cfg_path = tmp_path / "m" / "config.json"
    cfg = json.loads(cfg_path.read_text())
    cfg_path.write_text(json.dumps({**cfg, "format_version": 1}))      # the decoder that also took |Z_i⊥|
    from roomlight.errors import InputFileError

    with pytest.raises(InputFileError, match="format_version 1"):
        load_run_model(tmp_path / "m", device="cpu")
    cfg_path.write_text(json.dumps(cfg))
    (tmp_path / "m" / "model.safetensors").write_bytes(b"broken")

    with pytest.raises(InputFileError):
        load_run_model(tmp_path / "m", device="cpu")


# ----------------------------------------------------------------------------- training
def test_training_resumes_bit_identically(tmp_path):
    from roomlight.prior.data import write_toy_dataset
    from roomlight.prior.train import Trainer, get_train_preset

    write_toy_dataset(tmp_path / "data", 8, 32)
    cfg = get_train_preset("veni-d-tiny").replace(max_steps=6, val_fraction=0.0, progress=False, log_every=1,
                                                 val_every=0, ckpt_every=1000, image_every=0, num_workers=0)

    def run(out, until=None):
        t = Trainer(cfg, tmp_path / "data", tmp_path / out, device="cpu", note=lambda m: None)
        t.fit(until)
        t.close()
        return {k: v.detach().clone() for k, v in t.model.state_dict().items()}

    straight = run("straight")
    run("resumed", until=3)
    resumed = run("resumed")
    assert straight.keys() == resumed.keys()
    for k in straight:
        assert torch.equal(straight[k], resumed[k]), k
    assert any(not torch.equal(v, model("veni-d-tiny", dtype=torch.float32).state_dict()[k])
               for k, v in straight.items())  # it trained


def test_a_second_schedule_starts_from_the_first_runs_weights_and_refuses_another_family(tmp_path):
    """``train --config veni-d --init-from RUN``: the second schedule's network is the first run's best,
    tensor for tensor, with its normalisation; a run of our prior cannot seed a VENI run."""
    from roomlight.prior.data import write_toy_dataset
    from roomlight.errors import RoomlightError
    from roomlight.prior.train import Trainer, get_train_preset, resolve_run_model

    write_toy_dataset(tmp_path / "data", 8, 32)
    fast = dict(val_fraction=0.25, progress=False, log_every=1, val_every=2, ckpt_every=1000, image_every=0,
                num_workers=0)
    first = Trainer(get_train_preset("veni-d-tiny").replace(max_steps=4, **fast), tmp_path / "data",
                    tmp_path / "first", device="cpu", note=lambda m: None)
    first.fit()
    first.close()
    source = VeniVAE.from_pretrained(resolve_run_model(tmp_path / "first"))
    cfg = get_train_preset("veni-d-tiny").replace(max_steps=2, lr=5e-4, init_from=str(tmp_path / "first"), **fast)
    second = Trainer(cfg, tmp_path / "data", tmp_path / "second", device="cpu", note=lambda m: None)
    src_state = source.state_dict()
    for k, v in second.model.state_dict().items():
        assert torch.equal(v, src_state[k]), k
    assert second.model.normalization.to_dict() == source.normalization.to_dict()
    second.close()
    prior_cfg = get_train_preset("tiny").replace(max_steps=1, **fast)
    prior_run = Trainer(prior_cfg, tmp_path / "data", tmp_path / "prior", device="cpu", note=lambda m: None)
    prior_run.fit()
    prior_run.close()
    with pytest.raises(RoomlightError, match="architecture differs"):
        Trainer(cfg.replace(init_from=str(tmp_path / "prior")), tmp_path / "data", tmp_path / "third",
                device="cpu", note=lambda m: None)


# ----------------------------------------------------------------------------- fitting methods
@pytest.fixture(scope="module")
def tiny_scene(tmp_path_factory):
    from helpers_scene import make_tiny_scene

    return make_tiny_scene(tmp_path_factory.mktemp("scene"))


@pytest.fixture(scope="module")
def veni_models(tmp_path_factory):
    """A VENI and a VENI+D checkpoint (untrained, 16 x 32) saved where --set veni_model=... can name them."""
    root = tmp_path_factory.mktemp("veni")
    for name in ("veni-tiny", "veni-d-tiny"):
        model(name, dtype=torch.float32).save_pretrained(root / name)
    return root


@pytest.mark.mitsuba
def test_veni_methods_fit_their_own_models_at_infinity_and_as_2p5d_light(tiny_scene, veni_models, tmp_path):
    from roomlight.errors import RoomlightError
    from roomlight.fitting.inverse import FitConfig, fit_scene, make_light
    from roomlight.prior.model import PanoVAE, get_preset

    scene, _, _ = tiny_scene
    cfg = FitConfig(iterations=12, spp=4, eval_every=4, veni_model=str(veni_models / "veni-tiny"),
                    veni_d_model=str(veni_models / "veni-d-tiny"))
    prior = PanoVAE(get_preset("tiny"), NORM)
    env = make_light("veni", scene, cfg, model=prior)   # the prior given is not a VENI: the named one is taken
    mesh = make_light("veni-d", scene, cfg, model=prior)
    assert env.kind == "envmap" and mesh.kind == "mesh" and mesh.has_depth and not env.has_depth
    assert env.model.config == VENI_PRESETS["veni-tiny"] and mesh.model.config == VENI_PRESETS["veni-d-tiny"]
    given = VeniVAE.from_pretrained(veni_models / "veni-d-tiny")
    assert make_light("veni-d", scene, cfg, model=given).model is given  # --model wins when it fits the method
    with pytest.raises(RoomlightError, match="VENI model"):
        make_light("prior", scene, cfg, model=given)
    for method in ("veni", "veni-d"):
        r = fit_scene(scene, method, cfg, out_dir=tmp_path / method, progress=False)
        checks = [h["fixed_seed_loss"] for h in r.history if "fixed_seed_loss" in h]
        assert r.best_loss < checks[0], (method, checks)
        assert (tmp_path / method / "result.json").is_file()
    assert (tmp_path / "veni-d" / "emitter" / "emitter.ply").is_file()


def test_eval_prior_scores_veni_on_radiance_and_veni_d_on_depth_too(tmp_path):
    from roomlight.prior.data import PanoramaDataset, find_panoramas, write_toy_dataset
    from roomlight.errors import RoomlightError
    from roomlight.prior.eval import evaluate_prior
    from roomlight.prior.latent_fit import LatentFitConfig

    write_toy_dataset(tmp_path / "toy", 3, 32)
    ds = PanoramaDataset(find_panoramas(tmp_path / "toy"), (16, 32), root=tmp_path / "toy", calibrate=True)
    for name, with_depth in (("veni-tiny", False), ("veni-d-tiny", True)):
        m = model(name, dtype=torch.float32)
        rep = evaluate_prior(m, ds, LatentFitConfig(steps=8), progress=False, note=lambda s: None)
        assert rep["count"] == 3 and list(rep["rows"]) == ["encoder", "latent fit"]
        for row in rep["rows"].values():
            assert ("abs_rel" in row) == with_depth and math.isfinite(row["psnr_ldr"])
    with pytest.raises(RoomlightError, match="decodes depth"):
        evaluate_prior(model("veni-tiny", dtype=torch.float32), ds, LatentFitConfig(steps=2), progress=False,
                       note=lambda s: None, depth_only_fit=True)


@pytest.mark.mitsuba
def test_fit_photo_with_veni_d_places_its_2p5d_light_and_veni_shows_light_at_infinity(veni_models, tmp_path):
    from helpers_photo import bright_wall_room, make_tiny_photo
    from roomlight.fitting.photo import fit_photo, load_photo, photo_config

    rad, depth = bright_wall_room(16)
    make_tiny_photo(tmp_path / "case", rad, depth, key=None)
    case = load_photo(tmp_path / "case")
    cfg = photo_config("fast", render_size=32, geometry_size=32, iterations=4, eval_every=2, eval_spp=4,
                       checkpoint_every=0, init_samples=2, placement_steps=10,
                       veni_model=str(veni_models / "veni-tiny"), veni_d_model=str(veni_models / "veni-d-tiny"))
    mesh = fit_photo(case, "veni-d", cfg, progress=False)
    env = fit_photo(case, "veni", cfg, progress=False)
    # no view encoder: the paper's start for VENI+D; VENI's draws have no depth to rank them, so its mean room
    assert mesh.initial["init"] == "samples" and env.initial["init"] == "zero"
    with pytest.raises(RoomlightError, match="pass --init zero"):
        fit_photo(case, "veni", photo_config("fast", init="samples", veni_model=str(veni_models / "veni-tiny")),
                  progress=False)
    assert mesh.model.kind == "mesh" and env.model.kind == "envmap"
    assert mesh.model.light_model.model.config == VENI_PRESETS["veni-d-tiny"]
    assert len(mesh.result.history) >= 4 and len(env.result.history) >= 4
