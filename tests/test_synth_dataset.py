"""Procedural rooms, the dataset: determinism, resuming, splits/shards, the CLI, plausible panoramas."""

import hashlib

import numpy as np
import pytest

pytestmark = pytest.mark.mitsuba


@pytest.fixture(scope="module")
def small_set(tmp_path_factory):
    from roomlight.datagen.synth.dataset import SynthConfig, generate_dataset

    out = tmp_path_factory.mktemp("rooms")
    summary = generate_dataset(out, SynthConfig(n=4, seed0=10, height=8, spp=4), progress=False)
    return out, summary


def _digest(p):
    return hashlib.sha256(p.read_bytes()).hexdigest()


def test_same_seed_same_file_and_different_seeds_differ(small_set, tmp_path):
    from roomlight.core.io import read_panorama
    from roomlight.datagen.synth.dataset import SynthConfig, generate_dataset

    out, summary = small_set
    assert summary["failed"] == {} and summary["rendered"] == 4
    again = tmp_path / "again"
    generate_dataset(again, SynthConfig(n=4, seed0=10, height=8, spp=4), progress=False)
    files = sorted(out.glob("*/room-*.exr"))
    assert len(files) == 4
    for f in files:
        assert _digest(f) == _digest(again / f.parent.name / f.name)
    a, b = (read_panorama(f) for f in files[:2])
    assert a.metadata["room"] != b.metadata["room"] or not np.array_equal(a.depth, b.depth)


def test_resume_skips_finished_samples(small_set):
    from roomlight.datagen.synth.dataset import SynthConfig, generate_dataset

    out, _ = small_set
    s = generate_dataset(out, SynthConfig(n=4, seed0=10, height=8, spp=4), progress=False)
    assert s["rendered"] == 0 and s["skipped_existing"] == 4


def test_resume_with_other_shape_or_splits_is_refused(small_set):
    from roomlight.errors import RoomlightError
    from roomlight.datagen.synth.dataset import SynthConfig, generate_dataset

    out, _ = small_set
    before = sorted(p.name for p in out.glob("*/room-*.exr"))
    with pytest.raises(RoomlightError, match="height 8 -> 16"):
        generate_dataset(out, SynthConfig(n=4, seed0=10, height=16, spp=4), progress=False)
    with pytest.raises(RoomlightError, match="n 4 -> 5"):
        generate_dataset(out, SynthConfig(n=5, seed0=10, height=8, spp=4), progress=False)
    with pytest.warns(UserWarning, match="spp=4"):  # only the noise level changes: allowed, but said
        s = generate_dataset(out, SynthConfig(n=4, seed0=10, height=8, spp=9), progress=False)
    assert s["rendered"] == 0 and sorted(p.name for p in out.glob("*/room-*.exr")) == before


def test_cli_denoises_by_default_when_pyoidn_is_there(tmp_path, monkeypatch):
    import json
    import sys

    from click.testing import CliRunner

    from roomlight.cli.main import cli as main

    out = tmp_path / "d"
    r = CliRunner().invoke(main, ["synth", "--n", "1", "--res", "16x32", "--out", str(out), "--no-summary"])
    assert r.exit_code == 0, r.output
    assert json.loads((out / "synth.json").read_text()) == {"n": 1, "seed0": 0, "height": 16, "spp": 64,
                                                          "nadir_cap": 0.0, "denoise": True}
    monkeypatch.setitem(sys.modules, "pyoidn", None)
    out = tmp_path / "p"
    r = CliRunner().invoke(main, ["synth", "--n", "1", "--res", "16x32", "--out", str(out), "--no-summary"])
    assert r.exit_code == 0, r.output
    assert "without denoising" in r.output
    assert json.loads((out / "synth.json").read_text())["spp"] == 144


def test_splits_and_shards_partition_the_seed_range():
    from roomlight.datagen.synth.dataset import split_of

    n, seed0 = 50, 100
    splits = [split_of(s, seed0, n) for s in range(seed0, seed0 + n)]
    assert splits.count("test") == 5 and splits.count("val") == 5 and splits.count("train") == 40
    assert splits == sorted(splits, key=["train", "val", "test"].index)  # contiguous seed ranges
    k = 3
    shards = [[s for s in range(seed0, seed0 + n) if s % k == i] for i in range(k)]
    assert sorted(s for shard in shards for s in shard) == list(range(seed0, seed0 + n))


def test_rooms_are_lit_finite_and_positive(small_set):
    from roomlight.core.io import read_panorama

    out, _ = small_set
    for f in sorted(out.glob("*/room-*.exr")):
        p = read_panorama(f)
        assert np.isfinite(p.radiance).all() and (p.radiance >= 0).all()
        assert np.isfinite(p.depth).all() and (p.depth > 0).all()
        room = p.metadata["room"]
        assert room["lights_on"] + room["windows"] >= 1       # some emitter lights the room
        assert p.radiance.max() > 1.0                           # ... and reaches the capture point
        assert abs(p.metadata["exposure_factor"]) > 0


def test_bad_arguments_are_clean_errors(tmp_path):
    from roomlight.errors import RoomlightError
    from roomlight.datagen.synth.dataset import SynthConfig, generate_dataset

    with pytest.raises(RoomlightError, match="perfect square"):
        generate_dataset(tmp_path, SynthConfig(n=1, height=8, spp=10), progress=False)
    with pytest.raises(RoomlightError, match="shard"):
        generate_dataset(tmp_path, SynthConfig(n=1, height=8, spp=4, shard=(2, 2)), progress=False)


def test_every_lighting_scenario_renders_a_valid_panorama():
    """One room per scenario (sunny, overcast, dusk, night, interior): finite, non-negative
    radiance reaching most of the panorama, positive finite depth."""
    from roomlight.datagen.synth.dataset import render_room
    from roomlight.datagen.synth.rooms import generate_room

    want, seeds = {"sunny", "overcast", "dusk", "night", "interior"}, {}
    for seed in range(60):
        lighting = generate_room(seed).lighting
        seeds.setdefault(lighting, seed)
        if set(seeds) == want:
            break
    for lighting, seed in seeds.items():
        rad, depth, _ = render_room(seed, height=16, spp=4)
        rad, depth = rad.numpy(), depth.numpy()
        assert np.isfinite(rad).all() and (rad >= 0).all(), lighting
        assert np.isfinite(depth).all() and (depth > 0).all(), lighting
        assert (rad.max(-1) > 0).mean() > 0.9, lighting
