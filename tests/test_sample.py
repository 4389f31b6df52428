"""Tests of prior sampling, latent interpolation, probe placement/rendering and `roomlight sample`."""

from __future__ import annotations

import json
import math

import click
import numpy as np
import pytest
import torch
from click.testing import CliRunner

from roomlight.prior.data import PanoramaDataset, find_panoramas, toy_panorama, write_toy_dataset
from roomlight.prior.eval.samples import (CAMERA_TARGET, decode_latents, interpolate_latents, probe_layout, render_probes,
                                    sample_latents)
from roomlight.core.geometry.equirect import pixel_directions
from roomlight.core.io import read_exr, read_panorama
from roomlight.prior.model import Normalization, PanoVAE, get_preset


pytestmark = pytest.mark.usefixtures("one_torch_thread")


@pytest.fixture(scope="module")
def model_dir(tmp_path_factory):
    root = tmp_path_factory.mktemp("sample")
    write_toy_dataset(root / "data", 2, 32)
    ds = PanoramaDataset(find_panoramas(root / "data"), (16, 32), root=root / "data")
    norm = Normalization.from_data([(ds[i]["radiance"], ds[i]["depth"]) for i in range(2)])
    torch.manual_seed(0)
    PanoVAE(get_preset("tiny"), norm).save_pretrained(root / "model")
    return root


def test_latent_sampling_is_seeded():
    a, b = sample_latents(4, 16, seed=3), sample_latents(4, 16, seed=3)
    assert torch.equal(a, b) and not torch.equal(a, sample_latents(4, 16, seed=4))
    assert torch.allclose(sample_latents(4, 16, seed=3, temperature=0.5), 0.5 * a)


def test_interpolation_endpoints_and_slerp_norms():
    g = torch.Generator().manual_seed(0)
    z0, z1 = torch.randn(64, generator=g), torch.randn(64, generator=g)
    for mode in ("slerp", "lerp"):
        path = interpolate_latents(z0, z1, 5, mode)
        assert path.shape == (5, 64)
        assert torch.equal(path[0], z0) and torch.equal(path[-1], z1)
    lerp = interpolate_latents(z0, z1, 3, "lerp")
    torch.testing.assert_close(lerp[1], (z0 + z1) / 2)
    slerp = interpolate_latents(z0.double(), z1.double(), 5, "slerp")
    norms = slerp.norm(dim=1)
    want = torch.linspace(0, 1, 5, dtype=torch.float64) * (z1.norm() - z0.norm()) + z0.norm()
    torch.testing.assert_close(norms, want.double())
    # Directions are evenly spaced on the great circle.
    u = slerp / norms[:, None]
    angles = [math.acos(float((u[i] * u[i + 1]).sum().clamp(-1, 1))) for i in range(4)]
    assert max(angles) - min(angles) < 1e-9


def test_probes_sit_inside_the_room_and_in_view():
    _, depth = toy_panorama(7, 32)
    probes = probe_layout(depth)
    dirs = pixel_directions(32, 64, dtype=torch.float64)
    cam = torch.tensor(CAMERA_TARGET, dtype=torch.float64)
    cam = cam / cam.norm()
    assert len(probes) == 3
    dists = []
    for c, r in probes:
        c = torch.tensor(c, dtype=torch.float64)
        dist = float(c.norm())
        dists.append(dist)
        near = (dirs @ (c / dist)) > math.cos(math.radians(20.0))
        assert dist + r < float(depth.double()[near].min())  # clear of the emitter mesh
        assert math.degrees(math.acos(float(c @ cam / dist))) < 32.5 - math.degrees(math.asin(r / dist))
    assert len({round(d, 6) for d in dists}) == 3  # at different distances


def _cli():
    from roomlight.cli import sample
    from roomlight.cli.common import RoomlightGroup

    @click.group(cls=RoomlightGroup)
    def cli():
        pass

    cli.add_command(sample.command)
    return cli


def test_sample_cli_without_rendering_is_deterministic(model_dir, tmp_path):
    base = ["sample", "--model", str(model_dir / "model"), "--n", "3", "--no-render"]
    for name in ("a", "b"):
        res = CliRunner().invoke(_cli(), base + ["--out", str(tmp_path / name), "--seed", "5"])
        assert res.exit_code == 0, res.output
    res = CliRunner().invoke(_cli(), base + ["--out", str(tmp_path / "c"), "--seed", "6", "--no-emitters"])
    assert res.exit_code == 0, res.output
    a = read_panorama(tmp_path / "a" / "sample_002.exr")
    b = read_panorama(tmp_path / "b" / "sample_002.exr")
    c = read_panorama(tmp_path / "c" / "sample_002.exr")
    assert np.array_equal(a.radiance, b.radiance) and np.array_equal(a.depth, b.depth)
    assert not np.array_equal(a.radiance, c.radiance)
    assert a.metadata["seed"] == 5 and a.radiance.shape == (16, 32, 3)
    for name in ("samples.png", "latents.json", "sample_000/emitter.ply", "sample_000/scene.xml"):
        assert (tmp_path / "a" / name).exists(), name
    assert not (tmp_path / "c" / "sample_000").exists()
    model = PanoVAE.from_pretrained(model_dir / "model")
    z = torch.tensor(json.loads((tmp_path / "a" / "latents.json").read_text())["z"])
    rad, dep = decode_latents(model, z)
    np.testing.assert_allclose(a.depth, dep[2, 0].numpy(), rtol=1e-6)
    # the reported peak contrast is the written panorama's brightest / median luminance
    contrast = json.loads((tmp_path / "a" / "latents.json").read_text())["peak_contrast"]
    lum = a.radiance.astype(np.float64) @ np.array([0.2126, 0.7152, 0.0722])
    assert len(contrast) == 3
    assert contrast[2] == pytest.approx(lum.max() / np.sort(lum.ravel())[(lum.size - 1) // 2], rel=1e-5)
    assert "brightest pixel / median luminance: median" in res.output


def test_interpolation_cli_starts_at_the_first_panorama(model_dir, tmp_path):
    a, b = find_panoramas(model_dir / "data")
    res = CliRunner().invoke(_cli(), ["sample", "--model", str(model_dir / "model"), "--out", str(tmp_path / "i"),
                                      "--n", "4", "--interpolate", str(a), str(b)])
    assert res.exit_code == 0, res.output
    assert sorted(p.name for p in (tmp_path / "i").glob("interp_*.exr")) == [f"interp_{i:03d}.exr" for i in range(4)]
    assert (tmp_path / "i" / "interpolation.png").exists()
    model = PanoVAE.from_pretrained(model_dir / "model")
    ds = PanoramaDataset([a], (16, 32), root=model_dir / "data")
    with torch.no_grad():
        _, dep = model.decode(model.encode(ds[0]["radiance"][None], ds[0]["depth"][None]).mean)
    first = read_panorama(tmp_path / "i" / "interp_000.exr")
    np.testing.assert_allclose(first.depth, dep[0, 0].numpy(), rtol=1e-5)


@pytest.mark.mitsuba
def test_probe_render_and_figure(model_dir, tmp_path):
    rad, depth = toy_panorama(3, 16)
    img = render_probes(rad, depth, probe_layout(depth), resolution=24, spp=4)
    assert img.shape == (24, 24, 3) and bool(torch.isfinite(img).all()) and float(img.min()) >= 0
    assert float(img.mean()) > 0
    res = CliRunner().invoke(_cli(), ["sample", "--model", str(model_dir / "model"), "--out", str(tmp_path / "s"),
                                      "--n", "1", "--render-res", "16", "--spp", "2", "--no-emitters"])
    assert res.exit_code == 0, res.output
    probes = read_exr(tmp_path / "s" / "probes_000.exr")
    assert probes["R"].shape == (16, 16) and np.isfinite(probes["R"]).all()
    assert (tmp_path / "s" / "samples.png").stat().st_size > 1000


def test_sample_and_fit_pano_take_a_bundled_model_by_name_and_refuse_a_missing_path_in_one_line(tmp_path):
    from roomlight.cli.main import cli

    res = CliRunner().invoke(cli, ["sample", "--model", "lite", "--n", "1", "--no-render", "--no-emitters",
                                      "--out", str(tmp_path / "s")])
    assert res.exit_code == 0, res.output
    assert read_panorama(tmp_path / "s" / "sample_000.exr").radiance.shape == (64, 128, 3)
    for command in (["sample", "--out", str(tmp_path / "t")], ["fit-pano", str(tmp_path / "s" / "sample_000.exr")]):
        res = CliRunner().invoke(cli, [*command, "--model", str(tmp_path / "no-such-run")])
        assert res.exit_code != 0 and "no such file or directory" in res.output
        assert "Traceback" not in res.output
