"""The view encoder: lifting a view onto the sphere, training crops, the network, its training."""

from __future__ import annotations

import math
import shutil

import numpy as np
import pytest
import torch

from roomlight.core.geometry.lift import lift_resolution, lift_view
from roomlight.core.geometry.projection import panorama_to_perspective, perspective_directions
from roomlight.prior.model.view_encoder import ViewEncoder, view_exposure, view_input
from roomlight.prior.viewenc.crops import CropSpec, crop_rotation, cut_view, expose, occluder_mask, random_crop_spec


def _smooth_panorama(h=16):
    """(3, h, 2h) radiance and (1, h, 2h) depth that vary smoothly with direction."""
    from roomlight.core.geometry.equirect import pixel_directions

    d = pixel_directions(h, 2 * h, dtype=torch.float64)
    rad = torch.stack([1.0 + 0.5 * d[..., 0], 1.2 + 0.4 * d[..., 1], 0.8 + 0.3 * d[..., 2]]).float()
    depth = (2.0 + 0.5 * d[..., 0] + 0.3 * d[..., 2])[None].float()
    return rad, depth


def _slow_lift(points, radiance, rotation, h, w):
    """The lifting written pixel by pixel from the convention's formulas (docs/conventions.md)."""
    sums = np.zeros((h, w, 4))
    count = np.zeros((h, w))
    R = np.asarray(rotation)
    for p, c in zip(np.asarray(points, np.float64).reshape(-1, 3), np.asarray(radiance, np.float64).reshape(-1, 3)):
        x, y, z = R @ p
        r = math.sqrt(x * x + y * y + z * z)
        u = (math.atan2(x, -z) / (2 * math.pi)) % 1.0
        v = math.atan2(math.sqrt(x * x + z * z), y) / math.pi
        i, j = min(int(v * h), h - 1), min(int(u * w), w - 1)
        sums[i, j] += [c[0], c[1], c[2], math.log(r)]
        count[i, j] += 1
    mean = sums / np.maximum(count, 1)[..., None]
    return mean, count


def test_lift_matches_a_pixel_by_pixel_reference():
    rng = np.random.default_rng(3)
    points = rng.normal(size=(7, 9, 3)) * [1.0, 0.6, 1.5] + [0.2, 0.1, -2.0]
    radiance = rng.uniform(0, 3, size=(7, 9, 3))
    rot = crop_rotation(CropSpec(60.0, 7, 9, pitch_deg=12.0, roll_deg=-4.0, yaw_deg=33.0))
    part = lift_view(torch.from_numpy(points), torch.from_numpy(radiance), rot, (8, 16))
    mean, count = _slow_lift(points, radiance, rot, 8, 16)
    np.testing.assert_array_equal(part.count.numpy(), count)
    np.testing.assert_allclose(part.radiance.permute(1, 2, 0).numpy(), mean[..., :3], atol=1e-5)
    np.testing.assert_allclose(part.log_depth[0].numpy(), mean[..., 3], atol=1e-5)
    assert part.seen_fraction == pytest.approx((count > 0).mean())


def test_lift_leaves_out_invalid_and_degenerate_samples():
    points = torch.tensor([[0.0, 0.0, -1.0], [0.0, 0.0, 0.0], [float("nan"), 0.0, -1.0], [1.0, 0.0, 0.0]])
    radiance = torch.ones(4, 3)
    part = lift_view(points, radiance, np.eye(3), (4, 8), valid=torch.tensor([True, True, True, False]))
    assert float(part.count.sum()) == 1.0   # only the first: zero distance, NaN and the masked one go


def test_crop_directions_are_those_of_the_perspective_projection():
    rad, depth = _smooth_panorama()
    for spec in (CropSpec(70.0, 30, 40, 10.0, 3.0, 40.0), CropSpec(45.0, 24, 24, -20.0, -5.0, 250.0)):
        image, points = cut_view(rad, depth, spec)
        R = crop_rotation(spec)
        dirs = (points / points.norm(dim=-1, keepdim=True)).double() @ torch.from_numpy(R).T
        ref = perspective_directions(spec.height, spec.width, spec.fov_deg, forward=R @ [0, 0, -1.0],
                                     up=R @ [0, 1.0, 0], dtype=torch.float64)
        assert float((dirs - ref).abs().max()) < 1e-6
        view = panorama_to_perspective(rad[None].double(), spec.height, spec.width, spec.fov_deg,
                                       forward=R @ [0, 0, -1.0], up=R @ [0, 1.0, 0])[0].permute(1, 2, 0)
        np.testing.assert_allclose(image.numpy(), view.numpy(), atol=1e-5)


def test_a_crop_lifted_back_gives_the_panorama_where_it_is_seen():
    h = 32
    rad, depth = _smooth_panorama(h)
    spec = CropSpec(80.0, *lift_resolution(80.0, 4 / 3, 2 * h), pitch_deg=5.0, yaw_deg=120.0)
    image, points = cut_view(rad, depth, spec)
    part = lift_view(points, image, crop_rotation(spec), (h, 2 * h))
    well = part.count >= 6                      # cells covered by many samples, away from the view's border
    assert int(well.sum()) > 20
    err = (part.radiance - rad).abs().amax(0)[well]
    assert float(err.max()) < 0.05             # a box average of a smooth function at its cell
    assert float((part.log_depth[0] - depth[0].log()).abs()[well].max()) < 0.03


def test_lift_resolution_gives_three_samples_per_cell_at_the_centre():
    h, w = lift_resolution(90.0, 1.5, 128)
    f = w / (2 * math.tan(math.radians(45.0)))          # focal length in pixels
    assert (2 * math.pi / 128) * f == pytest.approx(3.0, rel=0.01)
    assert w / h == pytest.approx(1.5, rel=0.02)


def test_random_specs_stay_in_range_and_occluders_hide_part_of_the_view():
    rng = np.random.default_rng(0)
    for _ in range(50):
        s = random_crop_spec(rng, 128)
        assert 40 <= s.fov_deg <= 100 and abs(s.pitch_deg) <= 25 and abs(s.roll_deg) <= 5 and 0 <= s.yaw_deg < 360
    shares = [1 - occluder_mask(rng, 60, 80).mean() for _ in range(200)]
    assert min(shares) == 0.0 and 0.05 < max(shares) < 0.6


def test_expose_sets_the_log_average_and_clips():
    img = torch.rand(10, 12, 3) * 4 + 0.01
    out, a = expose(img, math.log(0.18))
    assert float(out.max()) <= 1.0
    y = 0.2126 * img[..., 0] + 0.7152 * img[..., 1] + 0.0722 * img[..., 2]
    assert math.exp(a) * math.exp(float(torch.log(y.double() + 1e-6).mean())) == pytest.approx(0.18, rel=1e-3)


def test_view_exposure_leaves_out_saturated_cells():
    part = lift_view(torch.tensor([[0.0, 0.0, -1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]),
                     torch.tensor([[0.5, 0.5, 0.5], [0.02, 0.02, 0.02], [1.0, 1.0, 1.0]]), np.eye(3), (8, 16))
    assert view_exposure(part) == pytest.approx(math.sqrt(0.5 * 0.02), rel=1e-4)


@pytest.fixture(scope="module")
def tiny_prior():
    from roomlight.prior.model import Normalization, PanoVAE
    from roomlight.prior.model.config import get_preset

    torch.manual_seed(0)
    return PanoVAE(get_preset("tiny"), Normalization((0.5, 0.5, 0.5, 0.7), (0.6, 0.6, 0.6, 0.5))).eval()


def test_from_prior_reads_a_fully_seen_panorama_as_the_prior_does(tiny_prior):
    rad, depth = _smooth_panorama(16)
    net = ViewEncoder.from_prior(tiny_prior)
    x = torch.cat([tiny_prior.normalization.normalize(rad[None], depth[None])[0], torch.ones(1, 16, 32)])
    z, s = net(x[None])
    torch.testing.assert_close(z, tiny_prior.encode(rad[None], depth[None]).mean, rtol=0, atol=1e-6)
    assert float(s.detach()) == 0.0


def test_view_input_divides_by_the_view_exposure_and_zeroes_unseen_cells(tiny_prior):
    rad, depth = _smooth_panorama(16)
    spec = CropSpec(60.0, 20, 30)
    image, points = cut_view(rad, depth, spec)
    part = lift_view(points, image * 7.0, crop_rotation(spec), (16, 32))
    x, k = view_input(part, tiny_prior.normalization)
    x1, k1 = view_input(lift_view(points, image, crop_rotation(spec), (16, 32)), tiny_prior.normalization)
    assert k == pytest.approx(7.0 * k1, rel=1e-5)
    torch.testing.assert_close(x, x1, atol=1e-5, rtol=0)     # the input does not depend on the photo's units
    assert bool((x[:, ~part.seen] == 0).all()) and bool((x[4] == part.seen.float()).all())


def test_withheld_depth_empties_the_depth_channel_and_nothing_else(tiny_prior):
    from roomlight.prior.model.view_encoder import DEPTH_CHANNEL

    rad, depth = _smooth_panorama(16)
    spec = CropSpec(60.0, 20, 30)
    image, points = cut_view(rad, depth, spec)
    part = lift_view(points, image, crop_rotation(spec), (16, 32))
    with_d, k = view_input(part, tiny_prior.normalization)
    without, k2 = view_input(part, tiny_prior.normalization, depth=False)
    assert k == k2
    assert float(with_d[DEPTH_CHANNEL][part.seen].abs().min()) > 0      # a z-scored depth is not 0 over a view
    assert bool((without[DEPTH_CHANNEL] == 0).all())
    keep = [c for c in range(5) if c != DEPTH_CHANNEL]
    assert torch.equal(with_d[keep], without[keep])
    # lifted at other distances (a photograph without depth): the same cells and radiance
    far = lift_view(points * 3.0, image, crop_rotation(spec), (16, 32))
    assert torch.equal(far.seen, part.seen)
    torch.testing.assert_close(view_input(far, tiny_prior.normalization, depth=False)[0], without)


def test_depth_dropout_withholds_that_share_of_views_and_zero_keeps_the_random_sequence(tiny_prior):
    from roomlight.prior.model.view_encoder import DEPTH_CHANNEL
    from roomlight.prior.viewenc.config import ViewTrainConfig
    from roomlight.prior.viewenc.views import training_view

    rad, depth = _smooth_panorama(16)
    norm = tiny_prior.normalization
    a, b = np.random.default_rng(5), np.random.default_rng(5)
    v0 = training_view(rad, depth, a, ViewTrainConfig(depth_dropout=0.0), norm)
    v1 = training_view(rad, depth, b, ViewTrainConfig(), norm, withhold=False)
    assert v0.depth_given and torch.equal(v0.x, v1.x)
    assert a.random() == b.random()                      # no extra draw: older runs replay the same views
    rng = np.random.default_rng(0)
    views = [training_view(rad, depth, rng, ViewTrainConfig(depth_dropout=0.5), norm) for _ in range(200)]
    given = np.array([v.depth_given for v in views])
    assert 0.4 < given.mean() < 0.6                      # binomial(200, 0.5): 4.2 sigma either side
    for v in views:
        assert bool((v.x[DEPTH_CHANNEL] == 0).all()) != v.depth_given
    with pytest.raises(Exception, match="out of range"):
        ViewTrainConfig(depth_dropout=1.5)


def test_training_with_depth_dropout_scores_validation_both_ways(tiny_prior, tmp_path):
    import json

    from roomlight.prior.data.toy import write_toy_dataset
    from roomlight.prior.model import PanoVAE
    from roomlight.prior.model.view_encoder import DEPTH_OPTIONAL_DIR
    from roomlight.prior.model.weights import file_sha256
    from roomlight.prior.viewenc.config import ViewTrainConfig
    from roomlight.prior.viewenc.trainer import ViewEncoderTrainer

    write_toy_dataset(tmp_path / "data" / "train", 6, height=16)
    write_toy_dataset(tmp_path / "data" / "val", 2, height=16, seed=100)
    cfg = ViewTrainConfig(batch_size=3, max_steps=2, val_every=1, ckpt_every=2, val_views=2, log_every=1,
                          progress=False, depth_dropout=0.5)
    run = ViewEncoderTrainer(cfg, tiny_prior, tmp_path / "data", tmp_path / "run", note=lambda *_: None)
    run.fit()
    vals = [json.loads(line) for line in (tmp_path / "run" / "log.jsonl").read_text().splitlines()]
    vals = [v for v in vals if v["event"] == "val"]
    assert vals and all(v["selection"] == pytest.approx(0.5 * (v["total"] + v["nodepth_total"])) for v in vals)
    best = json.loads((tmp_path / "run" / "best" / "best.json").read_text())
    assert best["selection"] == pytest.approx(min(v["selection"] for v in vals))
    # shipped beside the prior under its own name, it is found as the depth-optional encoder
    tiny_prior.save_pretrained(tmp_path / "prior")
    enc = ViewEncoder.from_pretrained(tmp_path / "run" / "best")
    enc.prior_sha256 = file_sha256(tmp_path / "prior" / "model.safetensors")
    enc.save_pretrained(tmp_path / "prior" / DEPTH_OPTIONAL_DIR, training_config=enc.metadata["training"])
    loaded = PanoVAE.from_pretrained(tmp_path / "prior")
    assert loaded.view_encoder is None and loaded.depth_optional_view_encoder is not None
    assert loaded.depth_optional_view_encoder.reads_without_depth
    assert not ViewEncoder.from_prior(tiny_prior).reads_without_depth


def test_saved_view_encoder_is_found_beside_its_prior_and_refused_beside_another(tiny_prior, tmp_path):
    from roomlight.prior.model import PanoVAE
    from roomlight.prior.model.weights import file_sha256

    tiny_prior.save_pretrained(tmp_path / "prior")
    net = ViewEncoder.from_prior(tiny_prior)
    net.prior_sha256 = file_sha256(tmp_path / "prior" / "model.safetensors")
    net.save_pretrained(tmp_path / "prior" / "view_encoder")
    loaded = PanoVAE.from_pretrained(tmp_path / "prior")
    assert loaded.view_encoder is not None
    assert "view_encoder" not in "".join(loaded.state_dict())      # not part of the prior's weights
    x = torch.randn(2, 5, 16, 32)
    torch.testing.assert_close(loaded.view_encoder(x)[0], net(x)[0])
    net.prior_sha256 = "0" * 64
    net.save_pretrained(tmp_path / "prior" / "view_encoder")
    with pytest.warns(UserWarning, match="other prior weights"):
        assert PanoVAE.from_pretrained(tmp_path / "prior").view_encoder is None


def test_training_resumes_exactly(tiny_prior, tmp_path):
    from roomlight.prior.data.toy import write_toy_dataset
    from roomlight.prior.viewenc.config import ViewTrainConfig
    from roomlight.prior.viewenc.trainer import ViewEncoderTrainer

    write_toy_dataset(tmp_path / "data" / "train", 6, height=16)
    write_toy_dataset(tmp_path / "data" / "val", 2, height=16, seed=100)
    cfg = ViewTrainConfig(batch_size=3, max_steps=4, val_every=2, ckpt_every=2, val_views=2, log_every=1,
                          progress=False)
    quiet = lambda *_: None  # noqa: E731
    whole = ViewEncoderTrainer(cfg, tiny_prior, tmp_path / "data", tmp_path / "a", note=quiet)
    whole.fit()
    part = ViewEncoderTrainer(cfg, tiny_prior, tmp_path / "data", tmp_path / "b", note=quiet)
    part.fit(until=2)
    again = ViewEncoderTrainer(cfg, tiny_prior, tmp_path / "data", tmp_path / "b", note=quiet)
    assert again.step == 2
    again.fit()
    for (name, a), (_, b) in zip(whole.net.state_dict().items(), again.net.state_dict().items()):
        torch.testing.assert_close(a, b, rtol=0, atol=0, msg=name)
    assert (tmp_path / "b" / "best" / "model.safetensors").exists()
    with pytest.raises(Exception, match="other settings"):
        ViewEncoderTrainer(cfg.replace(lr=1e-3), tiny_prior, tmp_path / "data", tmp_path / "b", note=quiet)


def test_a_photo_is_lifted_without_its_objects_and_with_its_pitch():
    from roomlight.core.geometry.equirect import direction_to_uv
    from roomlight.fitting.photo.camera import camera_rotation
    from roomlight.fitting.photo.case import PhotoCase
    from roomlight.fitting.photo.masks import ObjectLabels
    from roomlight.fitting.photo.start import photo_partial_panorama

    h = 32
    rad, depth = _smooth_panorama(h)
    spec = CropSpec(70.0, *lift_resolution(70.0, 4 / 3, 2 * h), pitch_deg=-15.0)
    image, points = cut_view(rad, depth, spec)
    labels = np.zeros(image.shape[:2], np.int32)
    labels[spec.height // 2:, : spec.width // 3] = 1              # an object in the lower left
    case = PhotoCase(0.5 * image.numpy(), (-points[..., 2]).numpy(), "z", spec.intrinsics,  # below saturation
                     ObjectLabels(labels, "binary", [1]), pitch_deg=-15.0)
    part = photo_partial_panorama(case, (h, 2 * h))
    well = part.count >= 6
    assert int(well.sum()) > 20
    assert float((part.radiance - 0.5 * rad).abs().amax(0)[well].max()) < 0.03
    assert float((part.log_depth[0] - depth[0].log()).abs()[well].max()) < 0.03
    # the cells of the object's pixels (away from its border) are not seen
    rays = (points / points.norm(dim=-1, keepdim=True)).double() @ torch.from_numpy(camera_rotation(-15.0, 0.0)).T
    inner = rays[spec.height // 2 + 3:, 1: spec.width // 3 - 3].reshape(-1, 3)
    u, v = direction_to_uv(inner)
    rows, cols = (v * h).long(), (u * 2 * h).long()
    hidden = torch.zeros(h, 2 * h, dtype=torch.bool)
    hidden[rows, cols] = True
    background = rays[: spec.height // 2 - 2].reshape(-1, 3)
    u, v = direction_to_uv(background)
    hidden[(v * h).long(), (u * 2 * h).long()] = False            # cells shared with the room stay seen
    assert bool(hidden.any()) and not bool(part.seen[hidden].any())


def test_the_start_resolves_auto_and_refuses_view_without_an_encoder(tiny_prior):
    from roomlight.errors import RoomlightError
    from roomlight.fitting.photo.start import resolve_start

    assert tiny_prior.view_encoder is None
    assert resolve_start("auto", tiny_prior) == "samples" and resolve_start("zero", tiny_prior) == "zero"
    with pytest.raises(RoomlightError, match="needs a prior with a view encoder"):
        resolve_start("view", tiny_prior)
    with pytest.raises(RoomlightError, match="expected one of"):
        resolve_start("best", tiny_prior)
    tiny_prior.set_view_encoder(ViewEncoder.from_prior(tiny_prior))
    try:
        assert resolve_start("auto", tiny_prior) == "view"
    finally:
        tiny_prior.set_view_encoder(None)


def test_an_encoder_trained_for_a_training_run_is_tied_to_its_best_weights(tiny_prior, tmp_path):
    """``--model RUN`` names a training run; the encoder must record the checksum of the weights it
    was trained for (RUN/best/model.safetensors), so that it loads beside them once bundled."""
    from roomlight.prior.data.toy import write_toy_dataset
    from roomlight.prior.model import PanoVAE
    from roomlight.prior.model.view_encoder import ViewEncoder
    from roomlight.prior.model.weights import file_sha256
    from roomlight.prior.viewenc.config import ViewTrainConfig
    from roomlight.prior.viewenc.trainer import ViewEncoderTrainer

    tiny_prior.save_pretrained(tmp_path / "run" / "best")
    write_toy_dataset(tmp_path / "data" / "train", 4, height=16)
    write_toy_dataset(tmp_path / "data" / "val", 2, height=16, seed=100)
    cfg = ViewTrainConfig(batch_size=2, max_steps=1, val_every=1, ckpt_every=1, val_views=2, log_every=1,
                          progress=False)
    ViewEncoderTrainer(cfg, tiny_prior, tmp_path / "data", tmp_path / "enc", prior_path=tmp_path / "run",
                       note=lambda *_: None).fit()
    expected = file_sha256(tmp_path / "run" / "best" / "model.safetensors")
    assert ViewEncoder.from_pretrained(tmp_path / "enc" / "best").prior_sha256 == expected
    shutil.copytree(tmp_path / "enc" / "best", tmp_path / "run" / "best" / "view_encoder")
    assert PanoVAE.from_pretrained(tmp_path / "run" / "best").view_encoder is not None


def _toy_view_trainer(prior, tmp_path, **settings):
    """(trainer, its settings) of a one-step view-encoder run on a few toy rooms (16 x 32)."""
    from roomlight.prior.data.toy import write_toy_dataset
    from roomlight.prior.viewenc.config import ViewTrainConfig
    from roomlight.prior.viewenc.trainer import ViewEncoderTrainer

    write_toy_dataset(tmp_path / "data" / "train", 4, height=16)
    write_toy_dataset(tmp_path / "data" / "val", 2, height=16, seed=100)
    cfg = ViewTrainConfig(batch_size=2, max_steps=1, val_every=1, ckpt_every=1, val_views=2, log_every=1,
                          progress=False, **settings)
    return ViewEncoderTrainer(cfg, prior, tmp_path / "data", tmp_path / "run", note=lambda *_: None), cfg


def _random_guess_terms(run, prior, seed: int):
    """(z (2, D), the views' seen cells (2, H, W), every loss term) of a random guess for the two validation views."""
    v = run.val
    torch.manual_seed(seed)
    z, s = torch.randn(2, prior.config.latent_dim), torch.zeros(2)
    seen = v["x"][:, -1] > 0.5
    return z, seen, run.losses(z, s, v["radiance"], v["depth"], v["mean"], v["s"], seen)


def test_the_irradiance_term_adds_its_weight_times_the_decoded_rooms_irradiance_error(tiny_prior, tmp_path):
    import json

    from roomlight.prior.losses.irradiance import irradiance_at_centre

    run, cfg = _toy_view_trainer(tiny_prior, tmp_path)
    v = run.val
    z, _, off = _random_guess_terms(run, tiny_prior, 1)
    run.cfg = cfg.replace(irradiance_weight=0.5)
    _, _, on = _random_guess_terms(run, tiny_prior, 1)
    # the term by hand: 14 normals' irradiance, log-L1 per channel
    rad_hat, _ = tiny_prior.decode(z)
    e_hat, e = irradiance_at_centre(rad_hat), irradiance_at_centre(v["radiance"])
    by_hand = (torch.log(e_hat + 1e-6) - torch.log(e + 1e-6)).abs().mean()
    assert float(on["irradiance"]) == pytest.approx(float(by_hand), rel=1e-4)
    assert float(on["total"] - off["total"]) == pytest.approx(0.5 * float(by_hand), rel=1e-4)
    # validation and the two references report the energy bias in stops
    run.cfg = cfg
    run.fit()
    log = [json.loads(line) for line in (tmp_path / "run" / "log.jsonl").read_text().splitlines()]
    ref = next(e for e in log if e["event"] == "reference")
    val = next(e for e in log if e["event"] == "val")
    assert {"zero_irradiance_stops", "full_irradiance_stops", "zero_irradiance_seen_stops"} <= set(ref)
    assert {"irradiance_stops", "irradiance_seen_stops"} <= set(val)


def test_the_display_term_adds_its_weight_times_the_error_validations_psnr_ldr_reads(tiny_prior, tmp_path):
    from roomlight.errors import RoomlightError
    from roomlight.prior.eval.metrics import psnr, to_ldr
    from roomlight.prior.viewenc.config import ViewTrainConfig

    run, cfg = _toy_view_trainer(tiny_prior, tmp_path)
    v = run.val
    z, _, off = _random_guess_terms(run, tiny_prior, 2)
    run.cfg = cfg.replace(display_weight=2.0)
    _, _, on = _random_guess_terms(run, tiny_prior, 2)
    # the metric's own path: per view PSNR LDR of the decoded room, back to its squared error
    rad_hat, _ = tiny_prior.decode(z)
    mse = (10.0 ** (-psnr(to_ldr(rad_hat, v["radiance"]), to_ldr(v["radiance"])) / 10.0)).mean()
    assert float(on["display"]) == pytest.approx(float(mse), rel=1e-4)
    assert float(off["display"]) == pytest.approx(float(mse), rel=1e-4)      # logged without its weight too
    assert float(on["total"] - off["total"]) == pytest.approx(2.0 * float(mse), rel=1e-4)
    with pytest.raises(RoomlightError, match="out of range"):
        ViewTrainConfig(display_weight=-1.0)
    # a run saved before the setting existed resumes without the term
    saved = cfg.to_dict()
    saved.pop("display_weight")
    assert ViewTrainConfig.from_dict(saved).display_weight == 0.0


def test_the_seen_matched_irradiance_term_scales_the_decoded_room_to_the_views_seen_cells(tiny_prior, tmp_path):
    from roomlight.core.geometry.equirect import pixel_solid_angles
    from roomlight.prior.losses.irradiance import irradiance_at_centre

    run, _ = _toy_view_trainer(tiny_prior, tmp_path, irradiance_weight=1.0, irradiance_seen_matched=True)
    v = run.val
    z, seen, terms = _random_guess_terms(run, tiny_prior, 2)
    assert bool(seen.any(-1).any(-1).all()) and not bool(seen.all())
    term = float(terms["irradiance"])
    # by hand, in float64: the decoded room scaled so its seen cells' solid-angle weighted mean log
    # luminance is the truth's, then the 14 normals' log-L1
    rad_hat = tiny_prior.decode(z)[0].double()
    rad = v["radiance"].double()
    w = seen.double() * pixel_solid_angles(*seen.shape[-2:], dtype=torch.float64)
    luma = torch.tensor([0.2126, 0.7152, 0.0722], dtype=torch.float64)

    def mean_log(r):
        return (w * torch.log(torch.einsum("c,bchw->bhw", luma, r) + 1e-6)).sum((1, 2)) / w.sum((1, 2))

    scaled = rad_hat * torch.exp(mean_log(rad) - mean_log(rad_hat))[:, None, None, None]
    e_hat, e = irradiance_at_centre(scaled), irradiance_at_centre(rad)
    by_hand = (torch.log(e_hat + 1e-6) - torch.log(e + 1e-6)).abs().mean()
    assert term == pytest.approx(float(by_hand), rel=1e-3)
    unmatched = (torch.log(irradiance_at_centre(rad_hat) + 1e-6) - torch.log(e + 1e-6)).abs().mean()
    assert abs(float(unmatched) - term) > 1e-3  # the scaling is not a no-op on these rooms


def test_a_run_without_the_irradiance_setting_resumes_as_weight_zero():
    from roomlight.prior.viewenc.config import ViewTrainConfig

    saved = ViewTrainConfig().to_dict()
    saved.pop("irradiance_weight")
    assert ViewTrainConfig.from_dict(saved).irradiance_weight == 0.0
    with pytest.raises(Exception, match="out of range"):
        ViewTrainConfig(irradiance_weight=-1.0)


def test_an_explicit_view_encoder_for_other_prior_weights_is_refused_in_one_line(tiny_prior, tmp_path):
    from roomlight.cli.common import InputError, set_view_encoder

    encoder = ViewEncoder.from_prior(tiny_prior)
    encoder.prior_sha256 = "b" * 64
    encoder.save_pretrained(tmp_path / "enc", training_config={})
    held, before = tiny_prior._weights_sha256, tiny_prior.view_encoder
    try:
        tiny_prior._weights_sha256 = "a" * 64
        with pytest.raises(InputError, match="trained for other prior weights"):
            set_view_encoder(tiny_prior, tmp_path / "enc")
        tiny_prior._weights_sha256 = "b" * 64
        set_view_encoder(tiny_prior, tmp_path / "enc")
        assert tiny_prior.view_encoder is not None and tiny_prior.view_encoder.prior_sha256 == "b" * 64
    finally:
        tiny_prior._weights_sha256 = held
        tiny_prior.set_view_encoder(before)
