"""``--scheduler``: synth and bench run on a local Dask cluster of two worker processes write the
same files as a serial run (the serial run is the reference)."""

from __future__ import annotations

import json

import numpy as np
import pytest

distributed = pytest.importorskip("distributed")

pytestmark = pytest.mark.mitsuba


@pytest.fixture(scope="module")
def cluster():
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                                  silence_logs=40) as c:
        yield c


def _pixels(path):
    from roomlight.core.io import read_exr

    return {k: np.asarray(v) for k, v in read_exr(path).items()}


@pytest.mark.slow
def test_synth_on_a_cluster_equals_a_serial_run(cluster, tmp_path):
    from roomlight.datagen.synth.dataset import SynthConfig, generate_dataset

    cfg = dict(n=3, seed0=7, height=8, spp=4)
    serial = generate_dataset(tmp_path / "serial", SynthConfig(**cfg), progress=False)
    spread = generate_dataset(tmp_path / "dask", SynthConfig(**cfg, scheduler=cluster), progress=False)
    assert serial["rendered"] == spread["rendered"] == 3 and not serial["failed"] and not spread["failed"]
    files = sorted(p.relative_to(tmp_path / "serial") for p in (tmp_path / "serial").rglob("room-*.exr"))
    assert len(files) == 3
    assert files == sorted(p.relative_to(tmp_path / "dask") for p in (tmp_path / "dask").rglob("room-*.exr"))
    for f in files:
        a, b = _pixels(tmp_path / "serial" / f), _pixels(tmp_path / "dask" / f)
        assert a.keys() == b.keys()
        for k in a:
            np.testing.assert_array_equal(a[k], b[k])
    # resuming on the cluster finds every file done
    again = generate_dataset(tmp_path / "dask", SynthConfig(**cfg, scheduler=cluster), progress=False)
    assert again["rendered"] == 0 and again["skipped_existing"] == 3


def test_bench_run_on_a_cluster_equals_a_serial_run(cluster, tmp_path):
    from roomlight.evaluation.bench.builder import BenchConfig, make_benchmark
    from roomlight.evaluation.bench.runner import run_benchmark
    from roomlight.core.examples import example_room
    from roomlight.core.io import write_panorama

    rad, depth = example_room(16)
    (tmp_path / "panos").mkdir()
    write_panorama(tmp_path / "panos" / "room.exr", (rad.numpy(), depth.numpy()))
    bench = tmp_path / "bench"
    make_benchmark(tmp_path / "panos", bench, BenchConfig(n=1, emitter_height=16, width=24, height=24, spp=4,
                                                          materials=("diffuse", "mirror")), progress=False)
    serial = run_benchmark(bench, tmp_path / "serial", ["oracle"], eval_spp=4, progress=False)
    spread = run_benchmark(bench, tmp_path / "dask", ["oracle"], eval_spp=4, progress=False, scheduler=cluster)
    assert sorted(serial.done) == sorted(spread.done) == ["room/diffuse/oracle", "room/mirror/oracle"]
    for case in serial.done:
        a = json.loads((tmp_path / "serial" / "cases" / case / "result.json").read_text())
        b = json.loads((tmp_path / "dask" / "cases" / case / "result.json").read_text())
        assert a["metrics"] == b["metrics"]
        np.testing.assert_array_equal(_pixels(tmp_path / "serial" / "cases" / case / "eval.exr")["R"],
                                      _pixels(tmp_path / "dask" / "cases" / case / "eval.exr")["R"])
    again = run_benchmark(bench, tmp_path / "dask", ["oracle"], eval_spp=4, progress=False, scheduler=cluster)
    assert not again.done and len(again.skipped) == 2
