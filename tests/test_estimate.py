"""roomlight estimate: the light from one ordinary photograph (no depth, no mask), the field of view from
the EXIF, and the refinement on the photograph's own pixels."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import torch
from click.testing import CliRunner
from PIL import Image

from roomlight.cli.main import cli
from roomlight.errors import RoomlightError
from roomlight.fitting.photo.estimate import DEFAULT_FOV, exif_fov, first_depth_guess

pytestmark = [pytest.mark.usefixtures("one_torch_thread")]


def _jpeg(path, size=(400, 300), f35=None, focal=None, res_x=None):
    rng = np.random.default_rng(0)
    img = Image.fromarray(rng.integers(0, 255, (size[1], size[0], 3), dtype=np.uint8))
    exif = Image.Exif()
    sub = {}
    if f35:
        sub[0xA405] = f35
    if focal:
        sub[0x920A] = focal
        sub[0xA20E] = res_x
        sub[0xA210] = 2  # inches
    if sub:
        exif[0x8769] = sub
    img.save(path, exif=exif.tobytes() if sub else b"")
    return path


def test_field_of_view_from_the_35mm_equivalent_focal_length_worked_by_hand(tmp_path):
    # 26 mm equivalent: diagonal fov 2 atan(43.267 / 52) = 79.52 deg; on a 400 x 300 frame the horizontal
    # half-angle has tan = tan(39.76 deg) * 400 / 500 = 0.66565, so fov_x = 2 atan(0.66565) = 67.30 deg.
    p = _jpeg(tmp_path / "phone.jpg", f35=26)
    fov, why = exif_fov(p, 400, 300)
    assert fov == pytest.approx(2 * math.degrees(math.atan(math.hypot(36, 24) / 52 * 0.8)), abs=1e-6)
    assert fov == pytest.approx(67.30, abs=0.01) and "35 mm" in why
    # Focal length + focal plane resolution: a 6.17 mm wide sensor (400 px at 400 / (6.17 / 25.4) px per
    # inch) behind a 4.4 mm lens: fov_x = 2 atan(6.17 / 8.8) = 70.06 deg.
    q = _jpeg(tmp_path / "compact.jpg", focal=4.4, res_x=400 / (6.17 / 25.4))
    fov, why = exif_fov(q, 400, 300)
    assert fov == pytest.approx(2 * math.degrees(math.atan(6.17 / 8.8)), abs=1e-3)
    assert exif_fov(_jpeg(tmp_path / "bare.jpg"), 400, 300)[0] is None


def test_the_first_depth_guess_is_the_floor_below_and_a_wall_beyond():
    rays = np.array([[0.0, -1.0, 0.0], [0.0, -0.5, -math.sqrt(0.75)], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
    d = first_depth_guess(rays[None], eye_height=1.5, distance=3.5)[0]
    np.testing.assert_allclose(d, [1.5, 3.0, 3.5, 3.5])


@pytest.fixture(scope="module")
def photo_png(tmp_path_factory):
    """A photograph rendered from a known room (the bright-wall room), saved as an 8-bit PNG with no EXIF."""
    from helpers_photo import bright_wall_room, make_tiny_photo

    from roomlight.core.color import linear_to_srgb
    from roomlight.fitting.photo.case import load_photo

    root = tmp_path_factory.mktemp("estimate")
    rad, depth = bright_wall_room(16)
    make_tiny_photo(root / "case", rad, depth, size=(48, 64), spp=32, pitch=-10.0)
    case = load_photo(str(root / "case"))
    png = root / "photo.png"
    Image.fromarray(np.rint(linear_to_srgb(np.clip(case.image, 0, 1)) * 255).astype(np.uint8)).save(png)
    return png, case


def test_a_photo_without_exif_gets_one_clear_line_and_the_outputs(photo_png, tmp_path):
    png, _ = photo_png
    r = CliRunner().invoke(cli, ["estimate", str(png), "--out", str(tmp_path / "e")])
    assert r.exit_code == 0, r.output
    notes = [line for line in r.output.splitlines() if "field of view" in line]
    assert len(notes) == 1 and f"assuming a {DEFAULT_FOV:g} degree" in notes[0] and "--fov" in notes[0], r.output
    assert "Traceback" not in r.output
    for name in ("panorama.exr", "emitter/emitter.ply", "emitter/radiance.exr", "probes.png", "result.json"):
        assert (tmp_path / "e" / name).is_file(), name
    rec = json.loads((tmp_path / "e" / "result.json").read_text())
    assert rec["fov_deg"] == DEFAULT_FOV and rec["fov_from"].startswith("default")
    assert rec["seconds_total"] < 5.0
    # bad input: one line, no stack trace
    for args, needle in ([str(tmp_path / "nothing.jpg")], "does not exist"), ([str(png), "--fov", "400"], "--fov"):
        r = CliRunner().invoke(cli, ["estimate", *args, "--out", str(tmp_path / "x")])
        assert r.exit_code != 0 and needle in r.output and "Traceback" not in r.output, r.output


def test_the_light_in_the_photographs_directions_matches_its_pixels_and_refine_brings_it_closer(photo_png):
    """The visible room is the light seen from its centre: after --refine the light's radiance in each
    pixel's direction is nearer the photograph's than the view encoder's guess, in log terms."""
    from roomlight.core.geometry.equirect import sample_equirect
    from roomlight.fitting.photo.estimate import _rays_room, estimate_light
    from roomlight.prior.model.runs import load_run_model
    from roomlight.demo import bundled_prior_path

    _, case = photo_png
    model = load_run_model(bundled_prior_path(), device="cpu")
    img = np.minimum(case.image, 1.0)
    rays = torch.from_numpy(_rays_room(case.intrinsics, case.pitch_deg, 0.0).reshape(-1, 3)).float()
    keep = (img.reshape(-1, 3).max(1) < 0.99) & (img.reshape(-1, 3).mean(1) > 1e-3)

    def log_error(est):
        seen = sample_equirect(torch.as_tensor(est.light.radiance).permute(2, 0, 1)[None], rays)[0].T.numpy()
        a, b = seen.mean(1)[keep], img.reshape(-1, 3).mean(1)[keep]
        return float(np.median(np.abs(np.log(np.maximum(a, 1e-6) / b))))

    plain = estimate_light(img, case.intrinsics, model, case.pitch_deg)
    refined = estimate_light(img, case.intrinsics, model, case.pitch_deg, refine_steps=40)
    assert refined.info["refine"]["loss_final"] < refined.info["refine"]["loss_first"]
    assert log_error(refined) < log_error(plain)
    assert log_error(refined) < 0.35  # within 40 % of the photograph's radiance on the median pixel


def test_a_known_depth_replaces_the_guess_and_sets_the_room_s_size(tmp_path):
    """In a room twice the guess's size, the decoded room in the photograph's directions is about the guess's
    size without --depth and the true size with it."""
    from helpers_photo import bright_wall_room, make_tiny_photo

    from roomlight.core.geometry.equirect import sample_equirect
    from roomlight.demo import bundled_prior_path
    from roomlight.fitting.photo.case import load_photo
    from roomlight.fitting.photo.estimate import _rays_room, estimate_light
    from roomlight.fitting.photo.unproject import radial_distance
    from roomlight.prior.model.runs import load_run_model

    rad, depth = bright_wall_room(16)
    make_tiny_photo(tmp_path / "big", rad, depth * 2.0, size=(48, 64), spp=16, pitch=-10.0)
    case = load_photo(str(tmp_path / "big"))
    model = load_run_model(bundled_prior_path(), device="cpu")
    true_r = radial_distance(case.depth, case.intrinsics, case.depth_kind)
    rays = torch.from_numpy(_rays_room(case.intrinsics, case.pitch_deg, 0.0).reshape(-1, 3)).float()

    def size_error(given, without_depth="guess"):
        est = estimate_light(np.minimum(case.image, 1.0), case.intrinsics, model, case.pitch_deg, depth=given,
                             without_depth=without_depth)
        seen = sample_equirect(torch.as_tensor(est.light.depth)[None, None], rays)[0, 0].numpy().reshape(true_r.shape)
        return float(np.median(np.abs(np.log(seen / true_r)))), est.info["depth"]

    (guessed, how_g), (given, how) = size_error(None), size_error(true_r.astype(np.float32))
    assert "guess" in how_g and how.get("given")
    assert guessed > 0.4          # the guess (3.5 m) against a 6 m room
    assert given < 0.15 < guessed
    with pytest.raises(RoomlightError, match="depth-optional"):   # the bundled prior has none
        size_error(None, "withheld")
    # and from the command line, one line for a depth of the wrong size
    np.save(tmp_path / "small.npy", np.ones((4, 4), np.float32))
    from roomlight.core.color import linear_to_srgb

    png = tmp_path / "big.png"
    Image.fromarray(np.rint(linear_to_srgb(np.clip(case.image, 0, 1)) * 255).astype(np.uint8)).save(png)
    r = CliRunner().invoke(cli, ["estimate", str(png), "--fov", "70", "--depth", str(tmp_path / "small.npy"),
                                 "--out", str(tmp_path / "e")])
    assert r.exit_code != 0 and "depth is 4x4" in r.output and "Traceback" not in r.output, r.output


def test_the_command_s_refine_steps_are_the_library_s():
    from roomlight.cli.estimate import command
    from roomlight.fitting.photo.estimate import REFINE_STEPS

    steps = next(p for p in command.params if p.name == "steps")
    assert steps.default == REFINE_STEPS


def test_a_prior_with_a_depth_optional_encoder_reads_the_photo_without_depth_on_request(photo_png, tmp_path):
    """--depth-optional-encoder: the prior's view_encoder_depth_optional/ reads the photograph with the depth
    channel empty (no depth is read: result.json says so); without the flag the guess is read as before."""
    import shutil

    from roomlight.demo import bundled_prior_path
    from roomlight.prior.model.runs import load_run_model
    from roomlight.prior.model.view_encoder import DEPTH_OPTIONAL_DIR, ViewEncoder
    from roomlight.prior.model.weights import file_sha256

    prior_dir = tmp_path / "prior"
    shutil.copytree(bundled_prior_path(), prior_dir)
    model = load_run_model(prior_dir, device="cpu")
    enc = ViewEncoder.from_prior(model)          # untrained, but marked as trained with depth withheld
    enc.prior_sha256 = file_sha256(prior_dir / "model.safetensors")
    enc.save_pretrained(prior_dir / DEPTH_OPTIONAL_DIR, training_config={"depth_dropout": 0.5})
    png, _ = photo_png
    runs = {}
    for flag in ([], ["--depth-optional-encoder"]):
        out = tmp_path / f"e{len(flag)}"
        r = CliRunner().invoke(cli, ["estimate", str(png), "--fov", "70", "--model", str(prior_dir), "--out", str(out),
                                     *flag])
        assert r.exit_code == 0, r.output
        runs[bool(flag)] = json.loads((out / "result.json").read_text())
    assert runs[True]["depth"] == {"withheld": True, "encoder": "view_encoder_depth_optional"}
    assert "guess" in runs[False]["depth"]
    assert runs[True]["view_log_exposure"] != runs[False]["view_log_exposure"]
