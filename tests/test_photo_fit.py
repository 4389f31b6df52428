"""Fitting photographs: materials under a known light, the joint fit of light and materials, resuming
an interrupted fit, and probes under the recovered 2.5D light against an env map, on rendered photos."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from helpers_photo import bright_wall_room, make_tiny_photo

pytestmark = pytest.mark.mitsuba


@pytest.fixture(scope="module")
def photo(tmp_path_factory):
    """A 64 x 48 photograph of two spheres (known principled materials) in a room lit mostly by its
    front wall, with its photo case folder and truth."""
    from roomlight.fitting.photo import load_photo
    from roomlight.fitting.photo.synthetic import read_truth

    folder = tmp_path_factory.mktemp("photo") / "case"
    rad, depth = bright_wall_room(16)
    make_tiny_photo(folder, rad, depth, key=None)
    return folder, load_photo(folder), read_truth(folder)


@pytest.fixture(scope="module")
def prior():
    from roomlight.demo import bundled_prior_path
    from roomlight.prior.model import PanoVAE

    return PanoVAE.from_pretrained(bundled_prior_path())


def _config(**changes):
    from roomlight.fitting.photo import photo_config

    base = dict(render_size=64, geometry_size=64, eval_every=10, eval_spp=16, checkpoint_every=0, init_samples=8,
                placement_steps=100)
    return photo_config("fast", **{**base, **changes})


def _known_light(truth):
    from roomlight.fitting.inverse.lights import DirectLight

    light = DirectLight("mesh", tuple(truth["radiance"].shape[:2]), init_radiance=truth["radiance"],
                        init_depth=truth["depth"], smooth_radiance=0.0, smooth_depth=0.0)
    for p in light.parameters():
        p.requires_grad_(False)
    return light


@pytest.mark.slow
def test_albedo_recovered_under_the_known_light(photo, one_torch_thread):
    """With the light and the camera's place in the room known (and each object's roughness and
    metallic held at their true values), fitting the photograph recovers every object's albedo
    to 0.05 per channel from the initial 0.5."""
    from roomlight.fitting.photo import ObjectMaterials, fit_photo

    _, case, truth = photo
    materials = ObjectMaterials(case.objects.ids, free=("albedo",))
    for label, m in truth["materials"].items():
        materials.set_values(label, roughness=m["roughness"], metallic=max(m["metallic"], 1e-4))
    fit = fit_photo(case, "known-light", _config(iterations=60, spp=16), light=_known_light(truth),
                    transform=truth["transform"], materials=materials, progress=False)
    checks = [h["fixed_seed_loss"] for h in fit.result.history if "fixed_seed_loss" in h]
    assert fit.result.best_loss < checks[0] / 5
    for entry in fit.materials.to_json():
        true = truth["materials"][entry["label"]]
        assert np.abs(np.array(entry["albedo"]) - true["albedo"]).max() < 0.05, (entry, true)
        assert entry["roughness"] == pytest.approx(true["roughness"], abs=1e-6)   # held: untouched by Adam


def test_joint_fit_of_light_and_materials(photo, prior, tmp_path, one_torch_thread):
    """The paper's real-image fit runs: light (z, s) and materials together lower the objective,
    the frustum and repulsion terms take part, and one step of z is at most latent_step_clip long."""
    from roomlight.fitting.photo import fit_photo

    _, case, _ = photo
    cfg = _config(iterations=8, spp=4, eval_every=4, frustum_points=64, repulsion_points=64)
    fit = fit_photo(case, "prior", cfg, model=prior, out_dir=tmp_path / "fit", progress=False)
    checks = [h["fixed_seed_loss"] for h in fit.result.history if "fixed_seed_loss" in h]
    assert fit.result.best_loss < checks[0]
    record = fit.result.history[1]
    for term in ("img", "rep", "frustum", "frustum_depth", "z_prior", "room_albedo"):
        assert term in record and np.isfinite(record[term]), term
    assert "albedo_prior" not in record  # the reflectance prior is off by default
    assert len(fit.fitter.points) == 2 * 64 + 64  # object points of both spheres + free-space points
    assert not torch.allclose(fit.materials.values(), torch.full_like(fit.materials.values(), 0.5))
    assert (tmp_path / "fit" / "history.jsonl").is_file()
    # the latent step clip (the paper: 0.1), on a step that Adam alone would make longer
    z = fit.model.latent
    steps = []
    for it in range(3):
        before = z.detach().clone()
        fit.fitter.step(100 + it)
        steps.append(float((z.detach() - before).norm()))
    assert max(steps) <= cfg.latent_step_clip + 1e-6 and min(steps) > 0.5 * cfg.latent_step_clip, steps


def test_a_photo_fit_anchors_at_its_own_start(photo, prior):
    """The anchor is the start the fit was given (z0 of the start), so the term is 0 before any step."""
    from roomlight.fitting.photo.fitter import _initial_light
    from roomlight.fitting.photo.geometry import build_geometry

    _, case, _ = photo
    cfg = _config(z_anchor=0.01, frustum_points=32, repulsion_points=32, init="samples")
    geometry = build_geometry(case, cfg)
    light, _, info = _initial_light("prior", geometry, cfg, prior, case)
    torch.testing.assert_close(light.z_start, light.z.detach())
    assert float(light.z_start.norm()) == pytest.approx(info["z_norm"], rel=1e-5) and info["z_norm"] > 0
    assert float(light.regularizers()["z_anchor"]) == 0.0


def test_the_start_level_moves_by_the_asked_stops(photo, prior):
    """start_exposure_ev = 1.5 starts every light 2^1.5 times as bright as the match to the background, the
    prior's (same latent) and the free env map's alike; nothing else about the start changes."""
    from roomlight.fitting.photo.fitter import _initial_light
    from roomlight.fitting.photo.geometry import build_geometry

    _, case, _ = photo
    starts = {}
    for ev in (0.0, 1.5):
        cfg = _config(start_exposure_ev=ev, frustum_points=32, repulsion_points=32, init="samples")
        geometry = build_geometry(case, cfg)
        starts[ev] = {m: _initial_light(m, geometry, cfg, prior, case) for m in ("prior", "direct-envmap")}
    (l0, _, i0), (l1, _, i1) = starts[0.0]["prior"], starts[1.5]["prior"]
    assert i1["exposure"] / i0["exposure"] == pytest.approx(2 ** 1.5, rel=1e-6)
    assert float(torch.exp(l1.s) / torch.exp(l0.s)) == pytest.approx(2 ** 1.5, rel=1e-5)
    torch.testing.assert_close(l0.z, l1.z)
    d0, d1 = starts[0.0]["direct-envmap"][2], starts[1.5]["direct-envmap"][2]
    assert d1["initial_radiance"] / d0["initial_radiance"] == pytest.approx(2 ** 1.5, rel=1e-6)


@pytest.mark.slow
def test_interrupted_fit_resumes_where_it_stopped(photo, prior, tmp_path, monkeypatch, one_torch_thread):
    """A fit interrupted after its fourth iteration and run again continues from the saved state
    and ends where an uninterrupted fit ends."""
    from roomlight.fitting.photo import fit_photo
    from roomlight.fitting.photo.fitter import STATE_FILE, PhotoFitter

    _, case, _ = photo
    cfg = _config(iterations=6, spp=2, eval_every=3, checkpoint_every=2, frustum_points=32, repulsion_points=32,
                  placement_steps=20, init_samples=2)
    whole = fit_photo(case, "prior", cfg, model=prior, out_dir=tmp_path / "whole", progress=False)

    original = PhotoFitter.step

    def interrupted(self, it):
        if it == 4:
            raise KeyboardInterrupt
        return original(self, it)

    monkeypatch.setattr(PhotoFitter, "step", interrupted)
    with pytest.raises(KeyboardInterrupt):
        fit_photo(case, "prior", cfg, model=prior, out_dir=tmp_path / "parts", progress=False)
    assert (tmp_path / "parts" / STATE_FILE).is_file()
    monkeypatch.setattr(PhotoFitter, "step", original)
    resumed = fit_photo(case, "prior", cfg, model=prior, out_dir=tmp_path / "parts", progress=False)
    assert [h["iteration"] for h in resumed.result.history] == list(range(7))
    assert resumed.result.best_iteration == whole.result.best_iteration
    for a, b in zip(whole.model.parameters(), resumed.model.parameters()):
        if a.requires_grad:
            assert torch.allclose(a, b, rtol=1e-3, atol=1e-4)  # Dr.Jit's parallel gradient sums vary ~1e-6
    lines = (tmp_path / "parts" / "history.jsonl").read_text().splitlines()
    assert len(lines) == 7
    # a saved state made under other settings is refused, with the reason
    from roomlight.errors import RoomlightError

    monkeypatch.setattr(PhotoFitter, "step", interrupted)
    with pytest.raises(KeyboardInterrupt):
        fit_photo(case, "prior", cfg, model=prior, out_dir=tmp_path / "again", progress=False)
    monkeypatch.setattr(PhotoFitter, "step", original)
    with pytest.raises(RoomlightError, match=r"other settings \(lr\)"):
        fit_photo(case, "prior", cfg.override(lr=0.05), model=prior, out_dir=tmp_path / "again", progress=False)
    with pytest.raises(RoomlightError, match="another input or method"):
        fit_photo(case, "prior-envmap", cfg, model=prior, out_dir=tmp_path / "again", progress=False)


@pytest.mark.slow
def test_mirror_probes_far_apart_are_better_under_the_2p5d_light(photo, prior, one_torch_thread):
    """Probes on the near and on the far sphere, rendered under the fitted lights and under the
    true room: the recovered 2.5D light shows each probe its surroundings better than the same
    prior fitted as an env map, at both positions, although the two see very different light.

    Both fits start as the paper does (``init = samples``) and run the ``fast`` preset's full 120 steps:
    with the bundled prior, after 40 or 80 steps the probe on the near sphere is not yet better under the
    2.5D light (mirror RMSE 1.02 against 1.00 at 80 steps) while the far one already is (0.53 against 1.77).

    The 2.5D fit from the view encoder's start does better still at both positions, in half the steps
    (measured at 60 steps, with the reflectance prior on the albedos: mirror RMSE 0.24 and 0.22, against
    0.47 and 0.41 from the paper's start at 120 and 1.31 and 1.23 for the env map; without the reflectance
    prior the paper's start reached 0.69 and 0.49 and the env map 1.11 and 1.52). From the view start the
    prior's env map is as good on this small scene (0.20 and 0.19, measured without the reflectance prior),
    so the claim above holds in the paper's setting only. With today's defaults (the visible room's albedo
    bound, no reflectance prior) the errors are 1.45 and 1.40 (2.5D) against 2.12 and 2.04 (env map) from
    the paper's start, and from the view's start 0.75 and 0.63 after 30 steps (0.84 and 0.71 after 60)."""
    from roomlight.core.light import Light
    from roomlight.fitting.photo import fit_photo
    from roomlight.fitting.photo.outputs import light_view
    from roomlight.fitting.photo.probes import LightView, ProbeSite, closeup_disc, render_probes

    _, case, truth = photo
    # The best iterate is checked every 20 steps: on this case both paper-start fits end at their best step
    # either way (the same errors as with checks every 10).
    cfg = _config(iterations=120, spp=8, init="samples", eval_every=20)
    fits = {m: fit_photo(case, m, cfg, model=prior, progress=False) for m in ("prior", "prior-envmap")}
    fits["prior from the view"] = fit_photo(case, "prior", cfg.override(init="view", iterations=30), model=prior,
                                            progress=False)
    g = fits["prior"].geometry
    sites = []
    for obj in g.objects:  # on top of each sphere
        i = int(np.argmax(obj.vertices[:, 1]))
        r = 0.06 * float(np.linalg.norm(obj.vertices[i]))
        sites.append(ProbeSite(tuple(obj.vertices[i] + obj.normals[i] * r * 1.02), r, obj.label))
    far_apart = np.linalg.norm(np.subtract(sites[0].center, sites[1].center))
    assert far_apart > 1.0  # metres, in the photograph's depth
    res = 32
    bsdfs = {lab: fits["prior"].materials.bsdf(lab) for lab in g.labels_present}
    t = truth["transform"]
    true = render_probes(LightView("truth", Light(truth["radiance"], truth["depth"], "mesh", t.matrix), t, bsdfs),
                         g.objects, sites, g.intrinsics, spp=128, resolution=res, materials=("mirror",), frame=False)
    discs = [closeup_disc(s, res) for s in sites]
    # the positions see different light: the true probes differ from each other
    t0, t1 = (true["mirror"][k][discs[k]].mean(0) for k in (0, 1))
    assert np.abs(t0 - t1).max() > 0.1 * max(t0.max(), t1.max())
    errors = {}
    for method, fit in fits.items():
        r = render_probes(light_view(fit), g.objects, sites, g.intrinsics, spp=128, resolution=res,
                          materials=("mirror",), frame=False)
        errors[method] = [float(np.sqrt(np.square(r["mirror"][k] - true["mirror"][k])[discs[k]].mean()))
                          for k in range(2)]
    for k in range(2):
        assert errors["prior"][k] < errors["prior-envmap"][k], errors
        assert errors["prior from the view"][k] < 0.6 * errors["prior"][k], errors


def test_the_view_start_keeps_the_camera_at_the_room_centre(photo, prior, one_torch_thread):
    """From the view encoder's start the decoded room is the camera's: no scale, no shift; from the
    paper's start the scene is placed inside a random room."""
    from roomlight.fitting.photo import fit_photo

    _, case, _ = photo
    assert prior.view_encoder is not None                       # the bundled prior ships one
    cfg = _config(iterations=0, placement_steps=20, init_samples=2)
    view = fit_photo(case, "prior", cfg, model=prior, progress=False)
    assert view.initial["init"] == "view" and 0 < view.initial["seen_fraction"] < 0.5
    assert view.transform.scale == 1.0 and not view.transform.translation.any()
    samples = fit_photo(case, "prior", cfg.override(init="samples"), model=prior, progress=False)
    assert samples.initial["init"] == "samples" and samples.transform.translation.any()
    assert view.containment["free_space_outside_share"] == 0.0 and view.containment["objects_outside_share"] == 0.0
