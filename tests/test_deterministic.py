"""The same fit twice gives the same numbers and images, bit for bit: by default (the adjoint pass on one
Dr.Jit worker) and with ``roomlight --deterministic`` (one worker throughout)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from helpers_cpu import spin_for

SRC = Path(__file__).parents[1] / "src"


def _fit(case: Path, out: Path, *flags, env_extra: dict | None = None) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(SRC), os.environ.get("PYTHONPATH", "")]),
           "ROOMLIGHT_THREADS": "2", "ROOMLIGHT_VARIANT": "llvm_ad_rgb", **(env_extra or {})}
    env.pop("ROOMLIGHT_DETERMINISTIC", None)
    env.pop("ROOMLIGHT_THREADS_AUTO", None)
    if not env.get("ROOMLIGHT_THREADS"):  # "" in env_extra: the program's own default
        env.pop("ROOMLIGHT_THREADS")
    if "ROOMLIGHT_PARALLEL_BACKWARD" not in (env_extra or {}):
        env.pop("ROOMLIGHT_PARALLEL_BACKWARD", None)
    cmd = [sys.executable, "-m", "roomlight.cli.main", *flags, "fit-photo", str(case), "--out", str(out),
           "--preset", "fast", "--iterations", "10", "--init", "samples", "--quiet", "--set", "render_size=64",
           "--set", "geometry_size=96", "--set", "probe_count=0", "--set", "eval_every=3",
           "--set", "placement_steps=20"]
    return subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=600)


def _numbers(out: Path) -> list:
    """Every number of the fit's history except wall times."""
    rows = [json.loads(line) for line in (out / "history.jsonl").read_text().splitlines()]
    return [{k: v for k, v in r.items() if "second" not in k and k != "time"} for r in rows]


@pytest.mark.mitsuba
@pytest.mark.slow
def test_the_same_fit_twice_is_bit_identical(tmp_path):
    """With two Dr.Jit workers in the adjoint pass (``ROOMLIGHT_PARALLEL_BACKWARD=1``) the same two fits
    differ (their histories differed in two of two tries: the workers scatter-add gradients into shared
    texels in varying order). The default fit (two workers, the adjoint on one) and the ``--deterministic``
    fit (one worker throughout) are equal number for number, so the default repeats itself as the
    one-worker fit does."""
    from roomlight.core.io import read_panorama
    from roomlight.fitting.photo.synthetic import example_photo_case

    case = tmp_path / "case"
    example_photo_case(case, width=96, height=72, spp=16)
    for name, flags in (("a", ()), ("b", ("--deterministic",))):
        r = _fit(case, tmp_path / name, *flags)
        assert r.returncode == 0, r.stderr[-2000:]
    assert _numbers(tmp_path / "a") == _numbers(tmp_path / "b")
    pa, pb = (read_panorama(tmp_path / n / "panorama.exr") for n in "ab")
    assert np.array_equal(pa.radiance, pb.radiance) and np.array_equal(pa.depth, pb.depth)
    ra, rb = (json.loads((tmp_path / n / "result.json").read_text()) for n in "ab")
    assert ra["objective"] == rb["objective"] and ra["materials"] == rb["materials"]
    # each record says what it was computed with: --threads 2 here (ROOMLIGHT_THREADS), one Dr.Jit worker
    # throughout under --deterministic
    assert ra["threads"] == {"torch": 2, "mitsuba": 2, "parallel_backward": False, "policy": "fixed",
                             "deterministic": False}
    assert rb["threads"] == {"torch": 2, "mitsuba": 1, "parallel_backward": False, "policy": "fixed",
                             "deterministic": True}


@pytest.mark.mitsuba
@pytest.mark.slow
def test_every_fitting_method_repeats_itself_bit_for_bit(tmp_path):
    """Each method of ``roomlight fit`` twice on the same scene (in one process, default settings): the
    same history, recovered maps and best iterate, number for number."""
    import torch

    from helpers_scene import make_tiny_scene
    from roomlight.fitting.inverse import FitConfig, fit_scene
    from roomlight.fitting.inverse.methods import METHODS
    from roomlight.prior.model import PanoVAE, get_preset
    from roomlight.prior.model.normalization import Normalization
    from roomlight.prior.model.veni import VENI_PRESETS, VeniVAE

    scene, _, _ = make_tiny_scene(tmp_path / "scene")
    norm = Normalization(mean=(0.3, 0.3, 0.3, 1.0), std=(0.5, 0.5, 0.5, 0.4))
    torch.manual_seed(0)
    prior = PanoVAE(get_preset("tiny"), norm)
    for name in ("veni-tiny", "veni-d-tiny"):
        VeniVAE(VENI_PRESETS[name], norm).save_pretrained(tmp_path / name)
    cfg = FitConfig(iterations=4, spp=4, eval_every=2, direct_resolution=(8, 16),
                    veni_model=str(tmp_path / "veni-tiny"), veni_d_model=str(tmp_path / "veni-d-tiny"))
    for method in METHODS:
        a, b = (fit_scene(scene, method, cfg, model=prior, progress=False) for _ in range(2))
        strip = lambda h: [{k: v for k, v in r.items() if "second" not in k and k != "time"} for r in h]  # noqa: E731
        assert strip(a.history) == strip(b.history), method
        assert np.array_equal(a.radiance, b.radiance) and a.best_iteration == b.best_iteration, method
        if a.depth is not None:
            assert np.array_equal(a.depth, b.depth), method


@pytest.mark.mitsuba
@pytest.mark.slow
def test_a_fit_beside_a_busy_process_repeats_the_fit_on_a_quieter_machine(tmp_path):
    """The thread count is the CPUs this process may use, not those the load leaves free: torch splits
    its float reductions by thread, so a count taken from the load gave other numbers beside another
    job (measured: a benchmark photo's probes moved by 0.03 dB, 1 thread against 2). The control: on
    this case one torch thread and two give other histories, so a count that followed the spinning
    process would show. The same fit with a spinning process beside it equals the fit without, number
    for number."""
    import multiprocessing

    from roomlight.fitting.photo.synthetic import example_photo_case

    case = tmp_path / "case"
    example_photo_case(case, width=96, height=72, spp=16)
    if len(os.sched_getaffinity(0)) >= 2:
        for n in ("1", "2"):
            r = _fit(case, tmp_path / f"threads{n}", env_extra={"ROOMLIGHT_THREADS": n})
            assert r.returncode == 0, r.stderr[-2000:]
        assert _numbers(tmp_path / "threads1") != _numbers(tmp_path / "threads2")
    quiet = _fit(case, tmp_path / "quiet", env_extra={"ROOMLIGHT_THREADS": ""})
    assert quiet.returncode == 0, quiet.stderr[-2000:]
    spinner = multiprocessing.get_context("fork").Process(target=spin_for, args=(600.0,), daemon=True)
    spinner.start()
    try:
        busy = _fit(case, tmp_path / "busy", env_extra={"ROOMLIGHT_THREADS": ""})
    finally:
        spinner.terminate()
        spinner.join()
    assert busy.returncode == 0, busy.stderr[-2000:]
    assert _numbers(tmp_path / "quiet") == _numbers(tmp_path / "busy")
