"""The capacity experiment: probe layout by ray casting, scores, the aggregate, and the whole run on
rooms whose answer is known (a furnace room, probes next to a wall light)."""

import json
import math

import numpy as np
import pytest
from click.testing import CliRunner

from roomlight.cli.main import cli
from roomlight.errors import RoomlightError
from roomlight.evaluation.experiments.capacity import CapacityConfig, run_capacity
from roomlight.evaluation.experiments.capacity_record import KINDS, room_cells, score_renders
from roomlight.evaluation.experiments.capacity_report import summarize_capacity
from roomlight.evaluation.experiments.layout import Caster, LayoutConfig, ProbeLayout, place_layout
from roomlight.core.render.raycast import sphere_directions

#: Small enough for a test: 32 x 64 panoramas, 24 x 24 probe images.
TINY = dict(pano_height=32, pano_spp=16, image_size=24, gt_spp=64, emitter_spp=64)


def run(*args):
    return CliRunner().invoke(cli, [str(a) for a in args], catch_exceptions=False)


# ---------------------------------------------------------------------------------------------
# Scores and summaries against hand computations
# ---------------------------------------------------------------------------------------------

def test_score_renders_is_the_rmse_over_each_probe_mask(rng):
    M, V, P, n = 2, 3, 3, 6
    gt = rng.random((M, 2, P, n, n, 3)).astype(np.float32)
    emit = rng.random((M, len(KINDS), V, P, n, n, 3)).astype(np.float32)
    emit2 = rng.random((M, P, n, n, 3)).astype(np.float32)
    masks = rng.random((P, n, n)) > 0.4
    rec = score_renders(gt, emit, emit2, masks, ["diffuse", "mirror"])["rmse"]
    for m, name in enumerate(["diffuse", "mirror"]):
        for k in range(P):
            pix = np.argwhere(masks[k])
            d = [float(np.sum((gt[m, 1, k, i, j] - gt[m, 0, k, i, j]) ** 2)) for i, j in pix]
            assert rec[name]["noise_floor"][k] == pytest.approx(math.sqrt(sum(d) / (3 * len(pix))), rel=1e-5)
            for ki, kind in enumerate(KINDS):
                for v in range(V):
                    diff = (emit[m, ki, v, k] - gt[m, 0, k])[masks[k]]
                    assert rec[name][kind][v][k] == pytest.approx(math.sqrt(np.mean(diff.astype(np.float64) ** 2)),
                                                                  rel=1e-5)


def _record(name, mesh, env, sphere, noise):
    """A room record whose per-viewpoint, per-probe errors are given as (V, P) arrays."""
    return {"name": name, "rmse": {"diffuse": {"noise_floor": [noise] * 3, "mesh_noise": [noise] * 3,
                                               "mesh": mesh.tolist(), "envmap": env.tolist(),
                                               "sphere": sphere.tolist()}}}


def test_room_cells_take_min_and_max_over_viewpoints_of_the_probe_average():
    mesh = np.array([[1.0, 2.0, 3.0], [4.0, 5.0, 6.0], [0.0, 1.0, 2.0]])   # probe averages 2, 5, 1
    env = 4 * mesh
    cells = room_cells(_record("r", mesh, env, 2 * mesh, 0.5))["diffuse"]
    assert cells["mesh"] == [1.0, 5.0]
    assert cells["envmap"] == [4.0, 20.0]
    assert cells["mesh_mean"] == pytest.approx(8.0 / 3.0)
    assert cells["noise_floor"] == 0.5


def test_summary_ratio_is_the_geometric_mean_over_rooms():
    mesh = np.ones((3, 3))
    recs = [_record("a", mesh, 2 * mesh, mesh, 0.1), _record("b", mesh, 8 * mesh, mesh, 0.1)]
    s = summarize_capacity(recs)["ratios"]["diffuse"]["envmap_over_mesh"]
    assert s["geomean"] == pytest.approx(4.0)
    assert (s["min"], s["max"], s["above_1"], s["in_paper_range"]) == (2.0, 8.0, 2, 1)
    assert s["ci95"][0] <= 4.0 + 1e-9 <= s["ci95"][1] + 1e-9


def test_settings_are_checked():
    with pytest.raises(RoomlightError, match="perfect square"):
        CapacityConfig(pano_spp=50)
    with pytest.raises(RoomlightError, match="unknown material"):
        CapacityConfig(materials=("velvet",))


# ---------------------------------------------------------------------------------------------
# Layout by ray casting
# ---------------------------------------------------------------------------------------------

@pytest.mark.mitsuba
def test_clearance_matches_the_distance_to_a_box_room(mi):
    from roomlight.datagen.synth.rooms import box_room
    from roomlight.datagen.synth.scene import build_scene

    caster = Caster(build_scene(box_room(size=(4.0, 2.7, 5.0), light=False)))
    for p in ([1.0, 1.0, 1.5], [3.5, 2.0, 4.2], [2.0, 0.3, 2.5]):
        true = min(p[0], 4.0 - p[0], p[1], 2.7 - p[1], p[2], 5.0 - p[2])
        got = caster.clearance(p)
        # rays meet a plane at d / cos(angle); the lattice has a direction within ~15 deg of any normal
        assert true - 1e-4 <= got <= true / math.cos(math.radians(15))
    assert caster.clearance([5.0, 1.0, 1.0]) == 0.0  # outside the room: rays escape
    assert caster.sees([0.5, 1.0, 0.5], [3.5, 2.0, 4.5])
    assert not caster.sees([0.5, 1.0, 0.5], [4.5, 1.0, 0.5])  # through the wall x = 4


def test_sphere_directions_are_unit_and_balanced():
    d = sphere_directions(256)
    assert np.allclose(np.linalg.norm(d, axis=1), 1.0)
    assert np.abs(d.mean(0)).max() < 0.01


@pytest.mark.mitsuba
def test_procedural_layout_keeps_clear_of_surfaces(mi):
    from roomlight.datagen.synth.rooms import generate_room
    from roomlight.datagen.synth.scene import build_scene

    room = generate_room(3)
    caster = Caster(build_scene(room))
    cfg = LayoutConfig()
    lay = place_layout(room, caster, np.random.default_rng(0), cfg)
    a, b, c = lay.probes
    assert cfg.pair_distance[0] <= np.linalg.norm(b - a) <= cfg.pair_distance[1]
    assert np.allclose(lay.viewpoints, [a, b, 0.5 * (a + b)])
    assert min(np.linalg.norm(c - a), np.linalg.norm(c - b)) >= cfg.third_distance
    for p in list(lay.probes) + [lay.viewpoints[2]]:
        assert caster.clearance(p, 512) >= 0.9 * cfg.clearance
    for v in lay.viewpoints:  # every probe is seen from every capture point
        assert all(caster.sees(v, p) for p in lay.probes)
    for (o, t), p in zip(lay.cameras, lay.probes):
        assert np.allclose(t, p) and np.linalg.norm(o - p) == pytest.approx(cfg.camera_distance)
    again = ProbeLayout.from_dict(json.loads(json.dumps(lay.to_dict())))
    assert np.allclose(again.probes, lay.probes, atol=1e-5)


# ---------------------------------------------------------------------------------------------
# Whole runs with known answers
# ---------------------------------------------------------------------------------------------

@pytest.mark.slow
@pytest.mark.mitsuba
def test_furnace_room_every_emitter_gives_half_the_uniform_radiance(mi, tmp_path, one_torch_thread):
    """A closed room whose every surface emits L and reflects nothing: a gray (albedo 0.5) diffuse
    probe anywhere reflects exactly 0.5 L, and every emitter built from any viewpoint's panorama
    shows the same uniform L. Calibrated units make L = 1, so every render averages 0.5."""
    from roomlight.evaluation.experiments.layout import cameras_for
    from roomlight.datagen.synth.rooms import box_room
    from roomlight.datagen.synth.scene import build_scene

    room = box_room(size=(4.0, 2.6, 4.0), albedo=(0.0, 0.0, 0.0), emission=(3.0, 3.0, 3.0))
    probes = np.array([[1.2, 1.2, 1.5], [2.8, 1.2, 1.5], [2.0, 1.0, 2.8]])
    lay = ProbeLayout(probes, 0.12, np.stack([probes[0], probes[1], 0.5 * (probes[0] + probes[1])]))
    lay.cameras = cameras_for(lay, Caster(build_scene(room)))
    cfg = CapacityConfig(materials=("diffuse",), **{**TINY, "image_size": 16, "gt_spp": 32, "emitter_spp": 32})
    run_capacity(tmp_path, cfg, rooms=[("furnace", room, lay)], progress=False)
    with np.load(tmp_path / "rooms" / "furnace" / "renders.npz") as z:
        gt, emit, masks = z["gt"], z["emit"], z["masks"]
    for k in range(3):
        assert gt[0, 0, k][masks[k]].mean() == pytest.approx(0.5, rel=0.02)
        for ki in range(len(KINDS)):
            for v in range(3):
                assert emit[0, ki, v, k][masks[k]].mean() == pytest.approx(0.5, rel=0.02), (KINDS[ki], v, k)
    # the same settings and seed give the same renders, bit for bit
    run_capacity(tmp_path / "again", cfg, rooms=[("furnace", room, lay)], progress=False)
    with np.load(tmp_path / "again" / "rooms" / "furnace" / "renders.npz") as z:
        assert np.array_equal(z["gt"], gt) and np.array_equal(z["emit"], emit)


@pytest.mark.mitsuba
@pytest.mark.slow
def test_wall_light_room_ranks_noise_floor_2p5d_and_env_map(mi, tmp_path, one_torch_thread):
    """Probes 0.8 m from a wall light: the 2.5D light follows the light's direction from each probe,
    the environment map does not. Expected order, per material: noise floor < 2.5D < env map; and
    an environment map relights the probe at its own capture point better than the other probe."""
    out = tmp_path / "cap"
    args = ["experiment", "capacity", "--out", out, "--wall-light-room", "--pano-res", 32, "--pano-spp", 64,
            "--image-size", 24, "--spp", 256, "--quiet"]
    r = run(*args)
    assert r.exit_code == 0, r.output
    doc = json.loads((out / "capacity.json").read_text())
    rec = doc["rooms"][0]
    for material, m in rec["rmse"].items():
        noise = np.mean(m["noise_floor"])
        mesh = np.asarray(m["mesh"]).mean(axis=1)     # per viewpoint, averaged over probes
        env = np.asarray(m["envmap"]).mean(axis=1)
        assert noise < mesh.mean(), material
        assert (mesh < env).all(), material
        env_pv = np.asarray(m["envmap"])              # (viewpoint, probe)
        assert env_pv[0, 0] < env_pv[1, 0] and env_pv[1, 1] < env_pv[0, 1], material
    md = (out / "capacity.md").read_text()
    assert "| Noise floor |" in md and "Environment map / 2.5D light" in md
    for name in ("probes-diffuse.png", "probes-mirror.png", "motivation.png", "ratios.png"):
        assert (out / "figures" / name).stat().st_size > 1000
    # a rerun reuses the room; other settings are refused with a one-line error
    before = (out / "rooms" / "wall-light" / "result.json").stat().st_mtime_ns
    r = run(*args)
    assert r.exit_code == 0 and "measured earlier and reused" in r.output
    assert (out / "rooms" / "wall-light" / "result.json").stat().st_mtime_ns == before
    r = CliRunner().invoke(cli, [str(a) for a in args[:-2]] + ["128", "--quiet"])
    assert r.exit_code == 2 and "other settings" in r.output and "Traceback" not in r.output
