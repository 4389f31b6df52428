"""Tests of roomlight.prior.eval: metrics against hand values and a slow SSIM reference, the prior
evaluation report and the eval-prior command."""

from __future__ import annotations

import json
import math

import click
import pytest
import torch
from click.testing import CliRunner

from roomlight.prior.data import PanoramaDataset, find_panoramas, write_toy_dataset
from roomlight.prior.eval import abs_rel, evaluate_prior, load_lpips, psnr, psnr_hdr, report_markdown, ssim, to_ldr
from roomlight.prior.eval.metrics import gaussian_window, peak_contrast, peak_error_stops
from roomlight.prior.latent_fit import LatentFitConfig
from roomlight.prior.model import Normalization, PanoVAE, get_preset


pytestmark = pytest.mark.usefixtures("one_torch_thread")


def ssim_reference(x, y, data_range=1.0, size=11, sigma=1.5):
    """Slow, obvious SSIM of two (H, W) images: explicit weighted sums over every valid window."""
    half = size // 2
    g = [math.exp(-((i - half) ** 2) / (2 * sigma**2)) for i in range(size)]
    s = sum(g)
    wts = [[g[i] * g[j] / (s * s) for j in range(size)] for i in range(size)]
    c1, c2 = (0.01 * data_range) ** 2, (0.03 * data_range) ** 2
    h, w = len(x), len(x[0])
    total, count = 0.0, 0
    for r in range(h - size + 1):
        for c in range(w - size + 1):
            mx = my = 0.0
            for i in range(size):
                for j in range(size):
                    mx += wts[i][j] * x[r + i][c + j]
                    my += wts[i][j] * y[r + i][c + j]
            vx = vy = cxy = 0.0
            for i in range(size):
                for j in range(size):
                    dx, dy = x[r + i][c + j] - mx, y[r + i][c + j] - my
                    vx += wts[i][j] * dx * dx
                    vy += wts[i][j] * dy * dy
                    cxy += wts[i][j] * dx * dy
            total += ((2 * mx * my + c1) * (2 * cxy + c2)) / ((mx * mx + my * my + c1) * (vx + vy + c2))
            count += 1
    return total / count


def test_ssim_matches_a_slow_reference():
    g = torch.Generator().manual_seed(0)
    a = torch.rand(2, 3, 14, 16, generator=g, dtype=torch.float64)
    b = (a + 0.15 * torch.randn(2, 3, 14, 16, generator=g, dtype=torch.float64)).clamp(0, 1)
    got = ssim(a, b)
    for k in range(2):
        want = sum(ssim_reference(a[k, c].tolist(), b[k, c].tolist()) for c in range(3)) / 3
        assert float(got[k]) == pytest.approx(want, abs=1e-10)
    assert torch.allclose(ssim(a, a), torch.ones(2, dtype=torch.float64))
    assert float(ssim(a, 1 - a)[0]) < 0.1
    assert float(gaussian_window().sum()) == pytest.approx(1.0)


def test_psnr_hdr_psnr_and_absrel_hand_values():
    t = torch.full((1, 3, 4, 8), 0.5)
    assert float(psnr(t + 0.1, t)) == pytest.approx(20.0, abs=1e-5)  # MSE 0.01 -> 20 dB
    assert float(psnr(t, t)) == math.inf
    hdr = torch.ones(1, 3, 4, 8)
    hdr[0, :, 0, 0] = 100.0
    assert float(psnr_hdr(hdr + 1.0, hdr)) == pytest.approx(40.0, abs=1e-9)  # peak 100, MSE 1
    d = torch.full((2, 1, 4, 8), 2.0)
    p = d.clone()
    p[0] *= 1.1
    p[1, 0, 0, :4] = 3.0  # 4 of 32 pixels off by 50 %
    assert abs_rel(p, d).tolist() == pytest.approx([0.1, 4 * 0.5 / 32])


def test_peak_error_in_stops_by_hand():
    t = torch.full((2, 3, 4, 8), 0.5)
    t[:, :, 1, 2] = 8.0                      # the light: luminance 8
    p = t.clone()
    p[0, :, 1, 2] = 2.0                      # two stops too dim
    p[1, :, 1, 2] = 0.5                      # light lost entirely: the brightest pixel is 0.5
    p[1, 1, 3, 7] = 64.0                     # ... but a green pixel of luminance 0.7152*64 + 0.5*(0.2126+0.0722)
    expected = [2.0, abs(math.log2((0.7152 * 64 + 0.5 * 0.2848) / 8.0))]
    assert peak_error_stops(p, t).tolist() == pytest.approx(expected, abs=1e-12)
    assert float(peak_error_stops(t, t)[0]) == 0.0


def test_peak_contrast_by_hand():
    r = torch.full((1, 3, 4, 8), 0.25)
    r[0, :, 0, 0] = 10.0                     # 31 pixels at 0.25 and one at 10: median 0.25
    assert float(peak_contrast(r)[0]) == pytest.approx(40.0, rel=1e-12)


def test_ldr_mapping_uses_the_targets_exposure():
    flat = torch.full((1, 3, 4, 8), 7.0)  # luminance 7 everywhere
    assert torch.allclose(to_ldr(flat), torch.full_like(flat, 0.18 ** (1 / 2.2)), atol=1e-5)
    # Against a reference, an exposure error stays visible.
    assert torch.allclose(to_ldr(2 * flat, reference=flat), torch.full_like(flat, 0.36 ** (1 / 2.2)), atol=1e-5)


@pytest.fixture(scope="module")
def setup(tmp_path_factory):
    root = tmp_path_factory.mktemp("evaldata")
    write_toy_dataset(root, 3, 32)
    (root / "broken.exr").write_bytes(b"nope")
    ds = PanoramaDataset(find_panoramas(root), (16, 32), root=root)
    good = [ds[i] for i in range(len(ds)) if "error" not in ds[i]]
    norm = Normalization.from_data([(it["radiance"], it["depth"]) for it in good])
    torch.manual_seed(0)
    return root, ds, PanoVAE(get_preset("tiny"), norm).eval()


def test_evaluate_prior_report(setup):
    _, ds, model = setup
    notes = []
    rep = evaluate_prior(model, ds, LatentFitConfig(steps=20), batch_size=2, depth_only_fit=True, progress=False,
                         note=notes.append)
    assert rep["count"] == 3 and [s["name"] for s in rep["skipped"]] == ["broken.exr"]
    assert list(rep["rows"]) == ["encoder", "latent fit", "latent fit (depth only)"]
    fn, reason = load_lpips()
    for row in rep["rows"].values():
        assert {"psnr_ldr", "ssim_ldr", "psnr_hdr", "peak_stops", "abs_rel"} <= set(row)
        assert ("lpips_ldr" in row) == (fn is not None)
    if fn is None:
        assert rep["lpips"].startswith("LPIPS not computed") and any("LPIPS" in n for n in notes)
    assert len(rep["per_image"]) == 3 and "latent fit" in rep["per_image"][0]
    md = report_markdown(rep)
    assert "| encoder |" in md and "| latent fit |" in md and "PSNR LDR" in md and "AbsRel" in md
    # The encoder row's numbers are the metrics of the decoded posterior means.
    items = [ds[i] for i in range(len(ds)) if "error" not in ds[i]]
    rad = torch.stack([it["radiance"] for it in items])
    dep = torch.stack([it["depth"] for it in items])
    with torch.no_grad():
        pr, pd = model.decode(model.encode(rad, dep).mean)
    assert rep["rows"]["encoder"]["abs_rel"] == pytest.approx(float(abs_rel(pd, dep).mean()), rel=1e-5)
    assert rep["rows"]["encoder"]["peak_stops"] == pytest.approx(float(peak_error_stops(pr, rad).mean()), rel=1e-5)


@pytest.fixture
def eval_cli(setup, tmp_path):
    """(click group holding eval-prior, the toy folder, the saved model's folder)."""
    from roomlight.cli import eval_prior
    from roomlight.cli.common import RoomlightGroup

    root, _, model = setup
    model.save_pretrained(tmp_path / "m")

    @click.group(cls=RoomlightGroup)
    def cli():
        pass

    cli.add_command(eval_prior.command)
    return cli, root, tmp_path / "m"


def test_eval_prior_cli_writes_markdown_and_json(eval_cli, tmp_path):
    cli, root, model_dir = eval_cli
    res = CliRunner().invoke(cli, ["eval-prior", "--model", str(model_dir), "--data", str(root),
                                   "--fit-steps", "5", "--out", str(tmp_path / "rep")])
    assert res.exit_code == 0, res.output
    assert "| latent fit |" in res.output
    rep = json.loads((tmp_path / "rep" / "eval_prior.json").read_text())
    assert rep["count"] == 3 and rep["fit"]["steps"] == 5
    assert (tmp_path / "rep" / "eval_prior.md").read_text().startswith("## Prior evaluation")


def test_radiance_only_evaluation_of_panoramas_without_depth(setup, eval_cli, tmp_path):
    """Real captures have no depth: --radiance-only fits z to radiance alone. On copies of the
    toy panoramas with the depth stripped (EXR and Radiance .hdr), it must give the same fit
    and the same radiance metrics as fitting radiance alone on the originals."""
    from roomlight.core.io import read_panorama, write_exr, write_hdr

    root, ds, model = setup
    plain = tmp_path / "plain"
    plain.mkdir()
    originals = [p for p in find_panoramas(root) if p.name != "broken.exr"]
    for k, p in enumerate(originals):
        rad = read_panorama(p).radiance
        if k == 0:
            write_hdr(plain / (p.stem + ".hdr"), rad)
        else:
            write_exr(plain / p.name, {c: rad[..., i] for i, c in enumerate("RGB")})
    cfg = LatentFitConfig(steps=15)
    ds_plain = PanoramaDataset(find_panoramas(plain), (16, 32), root=plain, require_depth=False)
    rep = evaluate_prior(model, ds_plain, cfg, batch_size=3, progress=False, note=lambda m: None,
                         radiance_only=True)
    assert list(rep["rows"]) == ["latent fit (radiance)"] and rep["count"] == 3
    row = rep["rows"]["latent fit (radiance)"]
    assert "abs_rel" not in row and {"psnr_ldr", "psnr_hdr", "peak_stops"} <= set(row)
    # Reference: the radiance-target fit on the originals (depth present but not in the objective).
    # The .hdr copy is quantised to 8-bit mantissas, so values agree to RGBE precision.
    ds_orig = PanoramaDataset(originals, (16, 32), root=root)
    ref = evaluate_prior(model, ds_orig, cfg.override(target="radiance"), batch_size=3, progress=False,
                         note=lambda m: None)
    by_name = {r["name"].split(".")[0]: r["latent fit"] for r in ref["per_image"]}
    for rec in rep["per_image"]:
        mine = rec["latent fit (radiance)"]
        want = by_name[rec["name"].split(".")[0]]
        tol = 0.05 if rec["name"].endswith(".hdr") else 1e-4
        assert mine["psnr_hdr"] == pytest.approx(want["psnr_hdr"], rel=tol), rec["name"]
    # Without the flag, a folder without depth is refused in one line that names the fix.
    cli, _, model_dir = eval_cli
    args = ["eval-prior", "--model", str(model_dir), "--data", str(plain), "--fit-steps", "3",
            "--out", str(tmp_path / "rep")]
    res = CliRunner().invoke(cli, args)
    assert res.exit_code != 0 and "Traceback" not in res.output and "--radiance-only" in res.output
    res = CliRunner().invoke(cli, args + ["--radiance-only"])
    assert res.exit_code == 0, res.output
    assert "| latent fit (radiance) |" in res.output


def test_eval_prior_names_the_latent_fit_objective(eval_cli, tmp_path):
    cli, root, model_dir = eval_cli
    args = ["eval-prior", "--model", str(model_dir), "--data", str(root), "--fit-steps", "3", "--limit", "2"]
    res = CliRunner().invoke(cli, args + ["--out", str(tmp_path / "paper")])
    assert res.exit_code == 0, res.output
    assert "from z = 0; squared error of the normalised channels (the paper's protocol)" in res.output
    res = CliRunner().invoke(cli, args + ["--out", str(tmp_path / "w"), "--set", "init_from_encoder=true",
                                          "--set", "depth_weight=4", "--set", "peak_weight=0.1"])
    assert res.exit_code == 0, res.output
    md = (tmp_path / "w" / "eval_prior.md").read_text()
    assert "from the encoder's mean" in md and "depth weighted 4×" in md and "0.1 × log-L1" in md
    assert "paper's protocol" not in md
    rep = json.loads((tmp_path / "w" / "eval_prior.json").read_text())
    assert rep["fit"]["depth_weight"] == 4 and rep["fit"]["peak_weight"] == 0.1
    # A report written before the objective had weights still renders, as the paper's protocol.
    for key in ("depth_weight", "peak_weight", "peak_fraction"):
        del rep["fit"][key]
    rep["fit"]["init_from_encoder"] = False
    assert "(the paper's protocol)" in report_markdown(rep)
    res = CliRunner().invoke(cli, args + ["--set", "peak_weight=-1"])
    assert res.exit_code != 0 and ">= 0" in res.output and "Traceback" not in res.output


def _sphere_laplacian(h: int, w: int) -> torch.Tensor:
    """(HW, HW) graph Laplacian of the smoothness prior's neighbour pairs, built pair by pair."""
    pairs = []
    for i in range(h):
        for j in range(w):
            pairs.append((i * w + j, i * w + (j + 1) % w))       # longitude, wrapping
            if i + 1 < h:
                pairs.append((i * w + j, (i + 1) * w + j))       # latitude
    for j in range(w // 2):                                      # across the poles: j <-> j + W/2
        pairs.append((j, j + w // 2))
        pairs.append(((h - 1) * w + j, (h - 1) * w + j + w // 2))
    lap = torch.zeros(h * w, h * w, dtype=torch.float64)
    for a, b in pairs:
        lap[a, a] += 1
        lap[b, b] += 1
        lap[a, b] -= 1
        lap[b, a] -= 1
    return lap


def test_pixel_level_fit_reaches_the_closed_form_minimiser():
    """Objective per channel: w_c mean (x - t)^2 + λ x^T L x / (HW); its minimiser solves
    (w_c I + λ L) x = w_c t, with L the Laplacian of the neighbour pairs (written out above)."""
    from roomlight.prior.latent_fit.pixel import fit_pixels

    torch.manual_seed(5)
    h, w = 4, 8
    norm = Normalization(mean=(0.2, 0.2, 0.2, 1.0), std=(0.6, 0.6, 0.6, 0.3))
    rad = torch.rand(1, 3, h, w) * 3
    dep = 1 + torch.rand(1, 1, h, w)
    lam = 0.2
    res = fit_pixels(rad, dep, LatentFitConfig(steps=1500, target="both", lr=0.05, lr_final=0.001),
                     normalization=norm, smoothness_weight=lam)
    target = norm.normalize(rad, dep)[0].double().reshape(4, -1)
    lap = _sphere_laplacian(h, w)
    for c in range(4):
        wc = 0.25
        ref = torch.linalg.solve(wc * torch.eye(h * w, dtype=torch.float64) + lam * lap, wc * target[c])
        torch.testing.assert_close(res.z[0, c].double().reshape(-1), ref, atol=2e-3, rtol=0)
    # without the smoothness term the fit is the target itself; radiance-only fits decode no depth
    free = fit_pixels(rad, None, LatentFitConfig(steps=300, target="radiance"), normalization=norm,
                      smoothness_weight=0.0)
    assert free.depth is None and float(psnr(to_ldr(free.radiance, rad), to_ldr(rad)).mean()) > 60


def test_pixel_level_rows_in_the_report(setup):
    _, ds, model = setup
    rep = evaluate_prior(model, ds, LatentFitConfig(steps=10), batch_size=4, progress=False, note=lambda m: None,
                         pixel_smoothness=0.05)
    assert list(rep["rows"]) == ["encoder", "latent fit", "pixel level (HDR)", "pixel level (HDRD)"]
    assert "abs_rel" not in rep["rows"]["pixel level (HDR)"] and "abs_rel" in rep["rows"]["pixel level (HDRD)"]
    md = report_markdown(rep)
    assert "| pixel level (HDR) |" in md and md.count("—") >= 1 and "0.05 × the smoothness prior" in md
