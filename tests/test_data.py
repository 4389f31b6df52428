"""Tests of roomlight.prior.data: file splits, the dataset loader (bad files skipped by name), the packed
cache, the resumable sampler, the augmentations (against analytic scenes) and statistics."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch

from roomlight.prior.data import (PackedCache, PanoramaDataset, ResumableBatchSampler, augment_batch, collate_panoramas,
                            dataset_statistics, load_training_pair, mirror, normalization_from_dataset, roll_azimuth,
                            split_files, tilt, tilt_rotations, toy_panorama, write_toy_dataset)
from roomlight.prior.data.splits import find_panoramas, hash_fraction
from roomlight.core.geometry.equirect import pixel_directions
from roomlight.core.io import exposure_calibrate, write_exr, write_panorama
from roomlight.prior.model import Normalization


pytestmark = pytest.mark.usefixtures("one_torch_thread")



def sphere_depth_map(h: int, w: int, center, radius: float) -> torch.Tensor:
    """(H, W) float64 distance from the origin to a sphere (centre, radius) enclosing it."""
    d = pixel_directions(h, w, dtype=torch.float64)
    c = torch.tensor(center, dtype=torch.float64)
    b = d @ c
    return b + torch.sqrt(b * b - (c @ c - radius**2))


def write_bad_files(root):
    """Three unusable files: garbage bytes, radiance without depth, width != 2 x height."""
    (root / "corrupt.exr").write_bytes(b"this is not an OpenEXR file at all")
    rad, _ = toy_panorama(1, 16)
    write_panorama(root / "nodepth.exr", rad.numpy())
    sq = np.ones((16, 16), np.float32)
    write_exr(root / "square.exr", {"R": sq, "G": sq, "B": sq, "Z": sq})
    return ["corrupt.exr", "nodepth.exr", "square.exr"]


# ------------------------------------------------------------------------------ splits
def test_split_by_hash_is_stable_and_folder_layout_is_used(tmp_path):
    write_toy_dataset(tmp_path / "flat", 20, 16)
    s = split_files(tmp_path / "flat", val_fraction=0.3)
    assert len(s["train"]) + len(s["val"]) == 20 and s["test"] == []
    assert {p.name for p in s["val"]} == {p.name for p in find_panoramas(tmp_path / "flat")
                                          if hash_fraction(p.name) < 0.3}
    # Adding files never moves an existing file to the other split.
    write_toy_dataset(tmp_path / "flat", 5, 16, seed=100)
    s2 = split_files(tmp_path / "flat", val_fraction=0.3)
    assert {p.name for p in s["val"]} <= {p.name for p in s2["val"]}
    for name in ("train", "val", "test"):
        write_toy_dataset(tmp_path / "split" / name, 2, 16, seed=hash(name) % 1000)
    s3 = split_files(tmp_path / "split")
    assert all(len(s3[k]) == 2 for k in ("train", "val", "test"))
    assert all(p.parent.name == "val" for p in s3["val"])


# ------------------------------------------------------------------------------ loading
def test_loader_reads_both_layouts_resamples_and_calibrates(tmp_path):
    rad, depth = toy_panorama(3, 32)
    write_panorama(tmp_path / "ours.exr", (rad.numpy(), depth.numpy()), half=False)
    r = rad.numpy()
    write_exr(tmp_path / "authors.exr", {"R": r[..., 0], "G": r[..., 1], "B": r[..., 2], "A": depth.numpy()},
              half=False)
    a_rad, a_dep, info = load_training_pair(tmp_path / "ours.exr", (16, 32))
    b_rad, b_dep, _ = load_training_pair(tmp_path / "authors.exr", (16, 32))
    assert a_rad.shape == (3, 16, 32) and a_dep.shape == (1, 16, 32)
    torch.testing.assert_close(a_rad, b_rad)
    torch.testing.assert_close(a_dep, b_dep)
    # Calibration at the file's resolution, then 2x2 block averaging.
    cal, factor = exposure_calibrate(rad.double().numpy())
    assert info["exposure_factor"] == pytest.approx(factor)
    want = torch.from_numpy(cal).permute(2, 0, 1)[None]
    want = torch.nn.functional.avg_pool2d(want, 2)[0].float()
    torch.testing.assert_close(a_rad, want, rtol=1e-5, atol=1e-6)
    torch.testing.assert_close(a_dep[0], torch.nn.functional.avg_pool2d(depth[None, None].double(), 2)[0, 0].float())
    _, sf_dep, sf_info = load_training_pair(tmp_path / "ours.exr", (16, 32), depth_units="scale-free")
    assert sf_info["depth_scale"] > 0
    assert float(torch.log(sf_dep.double()).mean()) == pytest.approx(0.0, abs=0.05)  # geometric mean ~1


def test_bad_files_are_reported_by_name_and_skipped(tmp_path):
    write_toy_dataset(tmp_path, 3, 16)
    bad = write_bad_files(tmp_path)
    files = find_panoramas(tmp_path)
    ds = PanoramaDataset(files, (16, 32), root=tmp_path)
    items = [ds[i] for i in range(len(ds))]
    errors = {it["name"]: it["error"] for it in items if "error" in it}
    assert sorted(errors) == bad
    assert "corrupt.exr" in errors["corrupt.exr"]
    assert "no depth" in errors["nodepth.exr"]
    assert "width" in errors["square.exr"] or "2" in errors["square.exr"]
    batch = collate_panoramas(items)
    assert batch["radiance"].shape == (3, 3, 16, 32) and batch["depth"].shape == (3, 1, 16, 32)
    assert sorted(n for n, _ in batch["skipped"]) == bad
    assert collate_panoramas([items[files.index(tmp_path / "corrupt.exr")]])["radiance"] is None


def test_packed_cache_matches_direct_loading_and_rebuilds_when_files_change(tmp_path):
    write_toy_dataset(tmp_path, 4, 32)
    bad = write_bad_files(tmp_path)
    files = find_panoramas(tmp_path)
    messages = []
    cache = PackedCache.open_or_build(tmp_path, files, (16, 32), progress=False, log=messages.append)
    assert cache.manifest["count"] == 4 and sorted(cache.errors) == bad
    assert len(messages) == 3 and all(m.startswith("skipping ") for m in messages)
    direct = PanoramaDataset(files, (16, 32), root=tmp_path)
    cached = PanoramaDataset(files, (16, 32), root=tmp_path, cache=cache)
    for i in range(len(files)):
        a, b = direct[i], cached[i]
        assert ("error" in a) == ("error" in b)
        if "error" not in a:
            # float16 log encoding: ~0.1 % relative error per value at these magnitudes.
            torch.testing.assert_close(b["radiance"], a["radiance"], rtol=4e-3, atol=1e-4)
            torch.testing.assert_close(b["depth"], a["depth"], rtol=2e-3, atol=0)
        else:
            assert b["error"] == a["error"]
    manifest = cache.path.with_suffix(".json")
    stamp = manifest.stat().st_mtime_ns
    assert PackedCache.open_or_build(tmp_path, files, (16, 32), progress=False).manifest["count"] == 4
    assert manifest.stat().st_mtime_ns == stamp  # reused, not rebuilt
    write_toy_dataset(tmp_path, 1, 32, seed=50)  # a new file ...
    rad, depth = toy_panorama(99, 32)
    assert files[0].name == "corrupt.exr"
    write_panorama(files[0], (rad.numpy(), depth.numpy()))  # ... and the corrupt one repaired
    files = find_panoramas(tmp_path)
    cache2 = PackedCache.open_or_build(tmp_path, files, (16, 32), progress=False, log=lambda m: None)
    assert cache2.manifest["count"] == 6 and "corrupt.exr" not in cache2.errors
    fresh = PanoramaDataset(files, (16, 32), root=tmp_path)[0]
    torch.testing.assert_close(PanoramaDataset(files, (16, 32), root=tmp_path, cache=cache2)[0]["radiance"],
                               fresh["radiance"], rtol=4e-3, atol=1e-4)


# ------------------------------------------------------------------------------ sampler
def test_sampler_is_seeded_resumable_and_splits_ranks():
    s = ResumableBatchSampler(10, 3, seed=5)
    it = iter(s)
    first = [next(it) for _ in range(9)]  # 3 epochs of 3 batches (one item dropped per epoch)
    for e in range(3):
        epoch = sum(first[3 * e:3 * e + 3], [])
        assert len(set(epoch)) == 9
    assert first[:3] != first[3:6]  # a new order every epoch
    resumed = iter(ResumableBatchSampler(10, 3, seed=5, start=4))
    assert [next(resumed) for _ in range(5)] == first[4:]
    assert [next(iter(ResumableBatchSampler(10, 3, seed=6))) for _ in range(1)] != first[:1]
    g = ResumableBatchSampler(12, 4, seed=1)
    r0 = ResumableBatchSampler(12, 4, seed=1, rank=0, world_size=2)
    r1 = ResumableBatchSampler(12, 4, seed=1, rank=1, world_size=2)
    for k in range(6):
        assert sorted(r0.batch(k) + r1.batch(k)) == sorted(g.batch(k))


# ------------------------------------------------------------------------------ augmentations
def test_roll_and_mirror_are_exact_rotations_and_reflections():
    h, w = 16, 32
    c = (0.4, -0.3, -0.7)
    d = sphere_depth_map(h, w, c, 2.0)[None, None]
    for s in (1, 5, 31):
        delta = 2 * math.pi * s / w
        c_rot = (c[0] * math.cos(delta) - c[2] * math.sin(delta), c[1], c[0] * math.sin(delta) + c[2] * math.cos(delta))
        torch.testing.assert_close(roll_azimuth(d, s), sphere_depth_map(h, w, c_rot, 2.0)[None, None],
                                   rtol=1e-12, atol=1e-12)
        per_sample = roll_azimuth(torch.cat([d, d]), torch.tensor([0, s]))
        torch.testing.assert_close(per_sample[1:], roll_azimuth(d, s), rtol=0, atol=0)
        torch.testing.assert_close(per_sample[:1], d, rtol=0, atol=0)
    torch.testing.assert_close(mirror(d), sphere_depth_map(h, w, (-c[0], c[1], c[2]), 2.0)[None, None],
                               rtol=1e-12, atol=1e-12)
    assert torch.equal(mirror(mirror(d)), d)
    flags = torch.tensor([True, False])
    both = mirror(torch.cat([d, d]), flags)
    assert torch.equal(both[0], mirror(d)[0]) and torch.equal(both[1], d[0])


def test_tilt_rotates_depth_like_the_scene_and_keeps_its_values():
    h, w = 64, 128
    c, rho = (0.5, 0.2, -0.6), 2.5
    d = sphere_depth_map(h, w, c, rho)[None, None]
    angle, axis_az = math.radians(7.0), 0.8
    rot = tilt_rotations(torch.tensor([angle]), torch.tensor([axis_az]))
    assert torch.allclose(rot[0] @ rot[0].T, torch.eye(3, dtype=torch.float64), atol=1e-12)
    axis = torch.tensor([math.cos(axis_az), 0.0, math.sin(axis_az)], dtype=torch.float64)
    assert torch.allclose(rot[0] @ axis, axis)  # the axis is horizontal and fixed
    c_rot = (rot[0] @ torch.tensor(c, dtype=torch.float64)).tolist()
    want = sphere_depth_map(h, w, c_rot, rho)[None, None]
    got = tilt(d, rot)
    # Bilinear resampling of a smooth field: small, second-order error; values keep their range.
    assert float(((got - want).abs() / want).max()) < 2e-3
    assert float(got.min()) >= float(d.min()) - 1e-9 and float(got.max()) <= float(d.max()) + 1e-9
    assert float(((got - d).abs() / d).max()) > 0.02  # and it really moved
    ident = tilt(d, tilt_rotations(torch.tensor([0.0]), torch.tensor([0.3])))
    torch.testing.assert_close(ident, d, rtol=1e-10, atol=1e-10)


def test_augment_batch_is_deterministic_per_generator_and_identity_when_disabled():
    rad = torch.rand(3, 3, 16, 32)
    dep = torch.rand(3, 1, 16, 32) + 1.0
    a = augment_batch(rad, dep, torch.Generator().manual_seed(3))
    b = augment_batch(rad, dep, torch.Generator().manual_seed(3))
    assert torch.equal(a[0], b[0]) and torch.equal(a[1], b[1])
    c = augment_batch(rad, dep, torch.Generator().manual_seed(4))
    assert not torch.equal(a[0], c[0])
    r, d = augment_batch(rad, dep, torch.Generator(), roll=False, flip=False, tilt_deg=0.0)
    assert torch.equal(r, rad) and torch.equal(d, dep)
    r, d = augment_batch(rad, dep, torch.Generator().manual_seed(1), tilt_deg=0.0)
    # Roll + mirror only permute pixels within each row: each row keeps its multiset of values.
    assert torch.equal(r.sort(-1).values, rad.sort(-1).values) and torch.equal(d.sort(-1).values, dep.sort(-1).values)


# ------------------------------------------------------------------------------ statistics
def test_statistics_match_a_direct_computation(tmp_path):
    write_toy_dataset(tmp_path, 3, 16)
    write_bad_files(tmp_path)
    ds = PanoramaDataset(find_panoramas(tmp_path), (16, 32), root=tmp_path)
    norm, skipped = normalization_from_dataset(ds)
    assert len(skipped) == 3
    good = [ds[i] for i in range(len(ds)) if "error" not in ds[i]]
    x = torch.cat([torch.cat([torch.log1p(it["radiance"].double()), torch.log(it["depth"].double())]).flatten(1)
                   for it in good], dim=1)
    assert np.allclose(norm.mean, x.mean(1).numpy(), atol=1e-9)
    assert np.allclose(norm.std, x.std(1, unbiased=False).numpy(), atol=1e-9)
    st = dataset_statistics(ds, progress=False)
    assert st["count"] == 3 and len(st["skipped"]) == 3
    assert Normalization.from_dict(st["normalization"]) == norm
    assert st["depth"]["min"] <= st["depth"]["median"] <= st["depth"]["max"]
    assert st["luminance"]["max"] >= st["luminance"]["p99"]


# ------------------------------------------------------------------------------ CLI
def test_data_cli_stats_pack_and_toy(tmp_path):
    import json

    from click.testing import CliRunner

    from roomlight.cli import data as data_cli

    runner = CliRunner()
    res = runner.invoke(data_cli.command, ["toy", "--n", "4", "--out", str(tmp_path / "d"), "--height", "16"])
    assert res.exit_code == 0, res.output
    (tmp_path / "d" / "bad.exr").write_bytes(b"garbage")
    res = runner.invoke(data_cli.command, ["stats", str(tmp_path / "d"), "--config", "tiny", "--split", "all",
                                           "--out", str(tmp_path / "stats.json")])
    assert res.exit_code == 0, res.output
    assert "log_depth" in res.output and "skipped bad.exr" in res.output
    st = json.loads((tmp_path / "stats.json").read_text())
    assert st["count"] == 4 and st["resolution"] == [16, 32] and st["skipped"][0]["name"] == "bad.exr"
    res = runner.invoke(data_cli.command, ["pack", str(tmp_path / "d"), "--config", "tiny", "--workers", "0"])
    assert res.exit_code == 0, res.output
    assert "4 panoramas packed, 1 skipped" in res.output
