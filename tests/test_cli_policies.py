"""Command-line policies: threads, repairs of bad radiance, validated options, ``--set`` everywhere,
the bundled prior as the default model, verified checkpoints and keyword-only writer options."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from helpers_cpu import spin_for
from roomlight.cli.main import cli
from roomlight.prior.data import write_toy_dataset
from roomlight.errors import InputFileError
from roomlight.core.examples import example_room
from roomlight.core.io import read_exr, write_panorama
from roomlight.prior.model import PanoVAE, get_preset
from roomlight.prior.model.normalization import Normalization

pytestmark = pytest.mark.usefixtures("one_torch_thread")
SRC = str(Path(__file__).parents[1] / "src")


def run(*args, env=None):
    return CliRunner().invoke(cli, [str(a) for a in args], env=env)


def python(code: str, **env) -> str:
    full = {**{k: v for k, v in os.environ.items() if k not in ("OMP_WAIT_POLICY", "ROOMLIGHT_THREADS")},
            "PYTHONPATH": os.pathsep.join([SRC, os.environ.get("PYTHONPATH", "")]), **env}
    r = subprocess.run([sys.executable, "-c", code], env=full, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-2000:]
    return r.stdout


@pytest.fixture(scope="module")
def model(tmp_path_factory):
    root = tmp_path_factory.mktemp("policy-model")
    rad, dep = example_room(16)
    norm = Normalization.from_data([(rad.permute(2, 0, 1), dep[None])])
    PanoVAE(get_preset("tiny"), norm).save_pretrained(root / "model")
    return root / "model"


def negative_pano(path: Path, count: int = 3) -> Path:
    rad, dep = example_room(32)
    rad = rad.numpy().copy()
    rad[1, :count, 0] = -0.5
    write_panorama(path, (rad, dep.numpy()), half=False)
    return path


# ----------------------------------------------------------------------------- threads
@pytest.mark.slow
def test_the_wait_policy_is_set_before_torch_loads_and_the_user_setting_wins():
    probe = ("import os, sys\n"
             "seen = {}\n"
             "class Spy:\n"
             "    def find_spec(self, name, path=None, target=None):\n"
             "        if name == 'torch' and 'wait' not in seen:\n"
             "            seen['wait'] = os.environ.get('OMP_WAIT_POLICY')\n"
             "sys.meta_path.insert(0, Spy())\n"
             "import roomlight.cli.main\n"
             "print(seen.get('wait'), os.environ.get('OMP_WAIT_POLICY'))\n")
    # whatever the load decided (passive beside busy processes, OpenMP's default when idle), it was
    # decided before torch loaded, since OpenMP reads it only then
    at_import, after = python(probe).split()
    assert at_import == after and at_import in ("PASSIVE", "None")
    assert python(probe, OMP_WAIT_POLICY="ACTIVE").split() == ["ACTIVE", "ACTIVE"]


@pytest.mark.slow
def test_threads_option_and_environment_variable_set_torch_threads():
    code = "import sys; from roomlight.cli.main import main; sys.argv = ['roomlight'] + sys.argv[1:]; main()"
    full = {**os.environ, "PYTHONPATH": os.pathsep.join([SRC, os.environ.get("PYTHONPATH", "")])}
    r = subprocess.run([sys.executable, "-c", code, "--threads", "3", "info"], env=full, capture_output=True,
                       text=True, timeout=300)
    assert "(3 threads)" in r.stdout, r.stdout + r.stderr
    r = subprocess.run([sys.executable, "-c", code, "info"], env={**full, "ROOMLIGHT_THREADS": "2"},
                       capture_output=True, text=True, timeout=300)
    assert "(2 threads)" in r.stdout, r.stdout + r.stderr
    r = subprocess.run([sys.executable, "-c", code, "info"], env={**full, "ROOMLIGHT_THREADS": "many"},
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 2 and "ROOMLIGHT_THREADS='many'" in r.stderr
    r = subprocess.run([sys.executable, "-c", code, "--threads", "auto", "info"], env=full, capture_output=True,
                       text=True, timeout=300)
    assert r.returncode == 0 and re.search(r"\(\d+ threads?\)", r.stdout), r.stdout + r.stderr
    r = subprocess.run([sys.executable, "-c", code, "--threads", "0", "info"], env=full, capture_output=True,
                       text=True, timeout=300)
    assert r.returncode == 2 and "0 is not a positive number of threads" in r.stderr and "Traceback" not in r.stderr


def test_auto_threads_are_the_free_cpus_this_process_may_use(monkeypatch):
    from roomlight.core import cpu

    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: {0, 1, 2, 3}, raising=False)
    monkeypatch.setattr(cpu, "busy_cpus", lambda interval=0.05, exclude_self=False: 1.4)
    assert cpu.measured_threads() == 3
    monkeypatch.setattr(cpu, "busy_cpus", lambda interval=0.05, exclude_self=False: 7.0)
    assert cpu.measured_threads() == 1


def test_own_cpu_time_matches_getrusage_and_a_busy_process_is_seen():
    """This process's ticks (what the re-check leaves out) against the kernel's other account of them,
    getrusage; and a process spinning next to us counts as busy whatever this one does."""
    import multiprocessing
    import resource
    import time

    from roomlight.core import cpu

    hz = os.sysconf("SC_CLK_TCK")
    r0, t0 = resource.getrusage(resource.RUSAGE_SELF), cpu._own_ticks()
    # 0.4 s of CPU in this process, however long a loaded machine takes to give it (wall time alone
    # left the loop with too little CPU when the other cores' work took this one's turn)
    c0, end = time.process_time(), time.perf_counter() + 20.0
    while time.process_time() - c0 < 0.4 and time.perf_counter() < end:
        pass
    r1, t1 = resource.getrusage(resource.RUSAGE_SELF), cpu._own_ticks()
    used = (r1.ru_utime + r1.ru_stime) - (r0.ru_utime + r0.ru_stime)
    assert used >= 0.39 and abs((t1 - t0) / hz - used) <= 2.5 / hz + 0.02
    ctx = multiprocessing.get_context("fork")
    spinner = ctx.Process(target=spin_for, args=(3.0,), daemon=True)
    spinner.start()
    try:
        time.sleep(0.3)
        assert cpu.busy_cpus(interval=0.5, exclude_self=True) >= 0.6
    finally:
        spinner.terminate()
        spinner.join()


def test_the_recheck_follows_the_load_only_under_auto(monkeypatch):
    import torch

    from roomlight.core import cpu
    from roomlight.core.render import variant

    before = torch.get_num_threads()
    monkeypatch.setenv("ROOMLIGHT_THREADS", "2")
    monkeypatch.delenv("ROOMLIGHT_DETERMINISTIC", raising=False)
    monkeypatch.setattr(cpu, "measured_threads", lambda exclude_self=False: 1)
    monkeypatch.delenv("ROOMLIGHT_THREADS_AUTO", raising=False)
    assert variant.recheck_threads() is None                # given by the user (or --threads): kept
    monkeypatch.setenv("ROOMLIGHT_THREADS_AUTO", "1")
    monkeypatch.setenv("ROOMLIGHT_DETERMINISTIC", "1")
    assert variant.recheck_threads() is None                # --deterministic: kept
    monkeypatch.delenv("ROOMLIGHT_DETERMINISTIC")
    notes = []
    try:
        assert variant.recheck_threads(note=notes.append) == 1
        assert torch.get_num_threads() == 1 and os.environ["ROOMLIGHT_THREADS"] == "1"
        assert len(notes) == 1 and "1 thread(s) for torch" in notes[0]
        assert variant.recheck_threads() is None             # unchanged load: nothing to do
    finally:
        torch.set_num_threads(before)
        monkeypatch.setenv("OMP_NUM_THREADS", str(before))


def test_only_auto_follows_the_load_and_its_mark_ends_with_the_request(monkeypatch):
    """By default ``roomlight`` takes every CPU it may use and never measures again; ``auto`` (option or
    environment) measures the load and marks the count, so that long commands measure again; any other
    request removes the mark, including ``--threads N`` replacing it and a later request without it, or
    the re-measurement between phases would change a fixed count mid-run."""
    from unittest import mock

    import torch

    from roomlight.core import cpu
    from roomlight.cli.threads import apply_thread_policy, default_threads
    from roomlight.core.render import variant

    before = torch.get_num_threads()
    monkeypatch.setattr(cpu, "measured_threads", lambda exclude_self=False: 2)
    monkeypatch.setattr("roomlight.cli.threads.measured_threads", cpu.measured_threads)
    monkeypatch.setattr("roomlight.cli.threads.available_cpus", lambda: 3)
    marked = lambda: os.environ.get("ROOMLIGHT_THREADS_AUTO") == "1"  # noqa: E731
    clean = {k: v for k, v in os.environ.items()
             if k not in ("ROOMLIGHT_THREADS", "ROOMLIGHT_THREADS_AUTO", "ROOMLIGHT_DETERMINISTIC", "OMP_NUM_THREADS")}
    try:
        with mock.patch.dict(os.environ, clean, clear=True):  # every variable restored afterwards
            default_threads()                       # the program's start, nothing asked: every CPU, fixed
            assert apply_thread_policy() == 3 and not marked()
            os.environ["ROOMLIGHT_THREADS"] = "auto"
            default_threads()                       # left for the policy to measure
            assert apply_thread_policy() == 2 and marked() and os.environ["ROOMLIGHT_THREADS"] == "2"
            assert apply_thread_policy(1) == 1 and not marked()   # --threads 1 replaces it
            assert variant.recheck_threads() is None and torch.get_num_threads() == 1
            assert apply_thread_policy("auto") == 2 and marked()  # --threads auto
            os.environ["ROOMLIGHT_THREADS_AUTO"] = "1"            # inherited from an earlier auto
            os.environ["ROOMLIGHT_THREADS"] = "3"
            assert apply_thread_policy() == 3 and not marked()
            os.environ["ROOMLIGHT_THREADS_AUTO"] = "1"
            del os.environ["ROOMLIGHT_THREADS"]                   # a later command that asks for nothing
            assert apply_thread_policy() is None and not marked()
    finally:
        torch.set_num_threads(before)


# ----------------------------------------------------------------------------- options
@pytest.mark.parametrize("args, expected", [
    (["--height", "-5"], "-5 is not in the range 1<=x<=8192"),
    (["--height", "0"], "0 is not in the range 1<=x<=8192"),
    (["--fill-nonfinite", "nan"], "expected a finite number"),
    (["--fill-nonfinite", "inf"], "expected a finite number"),
])
def test_emitter_options_are_validated_with_their_range(tmp_path, args, expected):
    r = run("emitter", "example", "--out", tmp_path / "o", *args)
    assert r.exit_code == 2 and expected in r.output and not (tmp_path / "o").exists()


def test_every_flag_an_error_suggests_exists_on_that_command(tmp_path, model):
    """The NaN and negative-radiance errors name a repair flag: each command that prints them has it."""
    rad, dep = example_room(32)
    rad = rad.numpy().copy()
    rad[0, 0, 0] = np.nan
    write_panorama(tmp_path / "nan.exr", (rad, dep.numpy()), half=False)
    negative_pano(tmp_path / "neg.exr")
    commands = {"emitter": ["emitter", "{p}", "--out", tmp_path / "o"],
                "fit-pano": ["fit-pano", "--model", model, "{p}", "--steps", 1, "--out", tmp_path / "o"]}
    for name, template in commands.items():
        for pano in ("nan.exr", "neg.exr"):
            r = run(*[str(tmp_path / pano) if a == "{p}" else a for a in template])
            assert r.exit_code == 2, r.output
            flags = re.findall(r"--[a-z][a-z-]+", r.stderr)
            assert flags, r.stderr
            options = {o for p in cli.get_command(None, name).params for o in p.opts}
            assert set(flags) <= options, (name, flags)


# ----------------------------------------------------------------------------- repairs
def test_fit_pano_refuses_negative_radiance_or_repairs_it_with_the_flag_and_reports_the_count(tmp_path, model):
    pano = negative_pano(tmp_path / "neg.exr", count=3)
    r = run("fit-pano", "--model", model, pano, "--steps", 2, "--out", tmp_path / "a")
    assert r.exit_code == 2 and "negative" in r.stderr and "--clamp-negative" in r.stderr
    r = run("fit-pano", "--model", model, pano, "--steps", 2, "--out", tmp_path / "b", "--clamp-negative")
    assert r.exit_code == 0, r.output
    assert "clamped 3 pixels with negative radiance to 0" in r.stderr


def test_train_skips_negative_radiance_or_repairs_it_with_the_flag(tmp_path):
    data = tmp_path / "data"
    write_toy_dataset(data, 4, 32)
    negative_pano(data / "neg.exr", count=2)
    args = ["train", "--data", data, "--config", "tiny", "--max-steps", 1, "--no-cache", "--set", "val_fraction=0",
            "--set", "progress=false"]
    r = run(*args, "--out", tmp_path / "r1")
    assert r.exit_code == 0, r.output
    assert re.search(r"skipping neg\.exr: .*negative values.*--clamp-negative", r.output), r.output
    r = run(*args, "--out", tmp_path / "r2", "--clamp-negative")
    assert r.exit_code == 0, r.output
    assert "clamped 2 pixels with negative radiance to 0" in r.output and "skipping neg.exr" not in r.output


# ----------------------------------------------------------------------------- --set and the default model
@pytest.mark.parametrize("command", [
    ["fit-pano", "--model", "{m}", "{p}", "--steps", 1],
    ["eval-prior", "--model", "{m}", "--data", "{d}", "--fit-steps", 1],
    ["sample", "--model", "{m}", "--n", 1, "--no-render", "--no-emitters"],
], ids=["fit-pano", "eval-prior", "sample"])
def test_set_is_shared_and_strict(tmp_path, model, command):
    data = tmp_path / "d"
    write_toy_dataset(data, 1, 32)
    args = [{"{m}": model, "{p}": next(data.glob("*.exr")), "{d}": data}.get(a, a) for a in command]
    r = run(*args, "--out", tmp_path / "o", "--set", "stpes=3")
    assert r.exit_code == 2 and "LatentFitConfig.stpes: unknown field (did you mean 'steps'?" in r.stderr, r.output


def test_fit_pano_set_reaches_the_latent_fit(tmp_path, model):
    write_toy_dataset(tmp_path / "d", 1, 32)
    pano = next((tmp_path / "d").glob("*.exr"))
    r = run("fit-pano", "--model", model, pano, "--out", tmp_path / "o", "--no-emitter", "--set", "steps=3",
            "--set", "lr_final=0.05")
    assert r.exit_code == 0, r.output
    fit = json.loads((tmp_path / "o" / "latent.json").read_text())["fit"]
    assert fit["steps"] == 3 and fit["lr_final"] == 0.05


def test_fit_with_the_prior_and_no_model_uses_the_bundled_prior(tmp_path):
    from roomlight.demo import bundled_prior_path

    if bundled_prior_path() is None:
        pytest.skip("no bundled prior in this installation")
    scene = {"objects": [{"id": "a", "shape": "knot"}],
             "views": {"input": {"camera": {"width": 8, "height": 8}, "objects": ["a"]}}}
    (tmp_path / "scene.json").write_text(json.dumps(scene))
    r = run("fit", tmp_path / "scene.json", "--method", "prior", "--out", tmp_path / "o")
    assert "needs --model" not in r.output
    assert "using the bundled prior" in r.stderr and str(bundled_prior_path()) in r.stderr


# ----------------------------------------------------------------------------- checkpoints and writers
def test_checksums_are_recorded_and_verified_and_older_checkpoints_still_load(tmp_path, model):
    import hashlib

    meta = json.loads((model / "config.json").read_text())
    assert meta["weights_sha256"] == hashlib.sha256((model / "model.safetensors").read_bytes()).hexdigest()
    old = tmp_path / "old"
    old.mkdir()
    (old / "model.safetensors").write_bytes((model / "model.safetensors").read_bytes())
    (old / "config.json").write_text(json.dumps({k: v for k, v in meta.items() if k != "weights_sha256"}))
    loaded = PanoVAE.from_pretrained(old)  # written before checksums: loads unverified
    assert loaded.config == get_preset("tiny")
    data = bytearray((old / "model.safetensors").read_bytes())
    data[-5] ^= 0xFF
    (old / "model.safetensors").write_bytes(bytes(data))
    meta_with = dict(meta)
    (old / "config.json").write_text(json.dumps(meta_with))
    with pytest.raises(InputFileError, match="model.safetensors: checksum mismatch"):
        PanoVAE.from_pretrained(old)


def test_writer_options_are_keyword_only(tmp_path):
    rad, dep = example_room(16)
    with pytest.raises(TypeError):
        write_panorama(tmp_path / "p.exr", rad.numpy(), dep.numpy())  # depth would have landed in `half`
    write_panorama(tmp_path / "p.exr", (rad.numpy(), dep.numpy()), half=False)
    assert read_exr(tmp_path / "p.exr")["Z"].shape == (16, 32)


def test_openmp_waits_passively_only_beside_busy_processes(monkeypatch):
    from roomlight.cli.threads import prepare_environment

    for name in ("OMP_WAIT_POLICY", "KMP_BLOCKTIME"):
        monkeypatch.delenv(name, raising=False)
    prepare_environment(busy=0.1)                      # an idle machine: OpenMP keeps its short spin
    assert "OMP_WAIT_POLICY" not in os.environ
    prepare_environment(busy=1.0)                      # another process holds a core: sleep when idle
    assert os.environ["OMP_WAIT_POLICY"] == "PASSIVE" and os.environ["KMP_BLOCKTIME"] == "0"
    monkeypatch.setenv("OMP_WAIT_POLICY", "ACTIVE")
    prepare_environment(busy=1.0)                      # the user's choice stays
    assert os.environ["OMP_WAIT_POLICY"] == "ACTIVE"


def test_a_record_names_the_threads_and_policy_it_was_made_with(monkeypatch):
    import torch

    from roomlight.core.render import variant

    monkeypatch.delenv("ROOMLIGHT_DETERMINISTIC", raising=False)
    monkeypatch.delenv("ROOMLIGHT_THREADS_AUTO", raising=False)
    monkeypatch.delenv("ROOMLIGHT_PARALLEL_BACKWARD", raising=False)
    # no variant active (or a GPU one): no Mitsuba workers to name, and the record switches nothing on
    monkeypatch.setattr(variant, "_active", None)
    monkeypatch.setattr(variant, "ensure_variant", lambda prefer=None: pytest.fail("the record activated Mitsuba"))
    rec = variant.thread_record()
    assert rec["torch"] == torch.get_num_threads() and rec["policy"] == "fixed" and rec["deterministic"] is False
    assert rec["mitsuba"] is None and rec["parallel_backward"] is False
    monkeypatch.setattr(variant, "_active", "cuda_ad_rgb")
    assert variant.thread_record()["mitsuba"] is None
    monkeypatch.setenv("ROOMLIGHT_PARALLEL_BACKWARD", "1")
    assert variant.thread_record()["parallel_backward"] is True
    monkeypatch.setenv("ROOMLIGHT_THREADS_AUTO", "1")
    monkeypatch.setenv("ROOMLIGHT_DETERMINISTIC", "1")
    rec = variant.thread_record()
    assert rec["policy"] == "auto" and rec["deterministic"] is True


def test_one_parser_reads_a_thread_request_for_the_option_and_the_environment():
    from roomlight.cli.threads import AUTO, parse_thread_request

    assert parse_thread_request("3") == 3 and parse_thread_request(" 12 ") == 12
    assert parse_thread_request(" Auto ") == AUTO and parse_thread_request(2) == 2
    for bad, why in (("0", "not a positive"), ("-2", "not a positive"), ("2.5", "neither"), ("", "neither"),
                     ("many", "neither")):
        with pytest.raises(ValueError, match=why):
            parse_thread_request(bad)
