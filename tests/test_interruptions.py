"""Long commands killed at a random point (SIGINT, SIGTERM, SIGKILL), then re-run, against an
uninterrupted run: the same result, bit for bit where the command is deterministic, and no item
lost or duplicated.

Each command runs in a child process (``python -m roomlight.cli.main``) so that the signal reaches
it exactly as a user's Ctrl-C, a scheduler's SIGTERM or the out-of-memory killer's SIGKILL would.
The point of the kill is random within the run (after the first sign of progress, plus a random
delay), seeded so that a failure can be replayed.
"""

from __future__ import annotations

import json
import os
import random
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from safetensors.torch import load_file

from roomlight.prior.data import write_toy_dataset

ENV = {**os.environ, "OMP_NUM_THREADS": "1", "ROOMLIGHT_THREADS": "1",
       "PYTHONPATH": os.pathsep.join([str(Path(__file__).parents[1] / "src"), os.environ.get("PYTHONPATH", "")])}


def roomlight(*args, check=True, timeout=300) -> subprocess.CompletedProcess:
    r = subprocess.run([sys.executable, "-m", "roomlight.cli.main", *map(str, args)], env=ENV, text=True,
                       capture_output=True, timeout=timeout)
    if check:
        assert r.returncode == 0, r.stderr[-3000:]
    return r


def kill_when(args, ready, sig: int, seed: int, max_delay: float, timeout: float = 240.0):
    """Start ``roomlight ARGS``, wait until ``ready()`` is true, wait a random delay, send ``sig``.

    Returns (exit status, its output: stdout and stderr together); 0 when the command finished before the
    signal could interrupt it (the caller tries again), an assertion error if it failed on its own.
    """
    # A test run started in the background by a non-interactive shell (`make test &`) inherits SIGINT
    # as ignored, and Python then never raises KeyboardInterrupt: give the child the default disposition,
    # as a terminal's foreground job has, so that the signal is really delivered.
    proc = subprocess.Popen([sys.executable, "-m", "roomlight.cli.main", *map(str, args)], env=ENV, text=True,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT,  # the notes go to either
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    t_end = time.monotonic() + timeout
    while not ready():
        assert proc.poll() is None, f"finished before it could be interrupted: {proc.stdout.read()[-2000:]}"
        assert time.monotonic() < t_end, "never became ready"
        time.sleep(0.02)
    time.sleep(random.Random(seed).uniform(0.0, max_delay))
    if proc.poll() is not None:  # done before the signal: no interruption to test
        err = proc.stdout.read()
        assert proc.returncode == 0, f"failed on its own: {err[-2000:]}"
        return 0, err
    proc.send_signal(sig)
    err, _ = proc.communicate(timeout=120)
    return proc.returncode, err


def train_steps(run: Path) -> list[int]:
    log = run / "log.jsonl"
    if not log.exists():
        return []
    out = []
    for line in log.read_text().splitlines():
        try:
            rec = json.loads(line)
        except json.JSONDecodeError:
            continue
        if rec.get("event") == "train":
            out.append(rec["step"])
    return out


def final_weights(run: Path, step: int) -> dict:
    return load_file(str(run / "checkpoints" / f"step-{step:08d}" / "model.safetensors"))


def assert_bit_identical(a: dict, b: dict) -> None:
    assert a.keys() == b.keys()
    differing = [k for k in a if not (a[k].shape == b[k].shape and bool((a[k] == b[k]).all()))]
    assert not differing, f"{len(differing)} tensors differ, e.g. {differing[:3]}"


STEPS = 60
TRAIN_ARGS = ["--config", "tiny", "--max-steps", STEPS, "--workers", 0, "--no-cache", "--set", "progress=false",
              "--set", "log_every=1", "--set", "val_fraction=0", "--set", "val_every=0", "--set", "ckpt_every=1000"]


@pytest.fixture(scope="module")
def toy(tmp_path_factory):
    root = tmp_path_factory.mktemp("toy")
    write_toy_dataset(root, 8, 32)
    return root


@pytest.fixture(scope="module")
def straight_run(toy, tmp_path_factory):
    run = tmp_path_factory.mktemp("straight") / "run"
    roomlight("train", "--data", toy, "--out", run, *TRAIN_ARGS)
    assert train_steps(run) == list(range(1, STEPS + 1))
    return run


@pytest.mark.slow
def test_train_killed_then_interrupted_then_resumed_is_bit_identical(toy, straight_run, tmp_path):
    """SIGKILL before the first checkpoint (the run must start afresh, each step logged once), then two
    Ctrl-Cs at random points (most land inside an optimiser step; each must checkpoint the step it logged
    last), then the rest: the final weights equal an uninterrupted run's, bit for bit.

    SIGTERM reaches the same handler as Ctrl-C (checked in-process below, without a training run)."""
    run = tmp_path / "run"
    code, _ = kill_when(["train", "--data", toy, "--out", run, *TRAIN_ARGS], lambda: len(train_steps(run)) >= 2,
                        signal.SIGKILL, seed=9, max_delay=0.3)
    assert code == -signal.SIGKILL
    assert not (run / "checkpoints").exists() or not any((run / "checkpoints").glob("step-*"))
    assert train_steps(run), "the killed run had logged steps"
    sig = signal.SIGINT
    for round_ in range(2):
        if round_ == 0:
            # The afresh run rewrites the killed run's log (a new file) before its first step: wait for that.
            killed_log = (run / "log.jsonl").stat().st_ino
            ready = lambda: ((run / "log.jsonl").stat().st_ino != killed_log  # noqa: E731
                             and max(train_steps(run), default=0) >= 2)
        else:
            before = max(train_steps(run))
            ready = lambda: max(train_steps(run), default=0) >= before + 2  # noqa: E731
        code, err = kill_when(["train", "--data", toy, "--out", run, *TRAIN_ARGS], ready, sig,
                              seed=10 * int(sig) + round_, max_delay=0.3)
        assert code == 128 + sig, err[-2000:]
        assert "Traceback" not in err
        if round_ == 0:
            assert "no checkpoint to resume from; starting afresh at step 0" in err
        stopped = max(train_steps(run))
        assert stopped < STEPS
        assert (run / "checkpoints" / f"step-{stopped:08d}").is_dir(), "the last logged step is the one checkpointed"
    r = roomlight("train", "--data", toy, "--out", run, *TRAIN_ARGS)
    assert f"step {stopped} of {STEPS}" in r.stderr + r.stdout
    assert train_steps(run) == list(range(1, STEPS + 1))  # each step once
    assert_bit_identical(final_weights(run, STEPS), final_weights(straight_run, STEPS))


# The command exactly as a user types it: ``--threads 1`` on the command line (not the environment, which
# the program treats differently), validation, the packed cache and the checkpoint interval left at their
# defaults, so the interrupted run crosses validations, image writing and periodic checkpoints.
USER_STEPS = 150
USER_TRAIN = ["--threads", 1, "train", "--config", "tiny", "--batch-size", 4, "--max-steps", USER_STEPS,
              "--workers", 0, "--seed", 5, "--set", "progress=false"]
USER_ENV = {k: v for k, v in ENV.items() if k not in ("ROOMLIGHT_THREADS", "OMP_NUM_THREADS")}


@pytest.fixture(scope="module")
def user_toy(tmp_path_factory):
    root = tmp_path_factory.mktemp("user-toy")
    write_toy_dataset(root, 24, 16)
    return root


def run_user_train(data: Path, out: Path) -> None:
    r = subprocess.run([sys.executable, "-m", "roomlight.cli.main", *map(str, USER_TRAIN), "--data", data,
                        "--out", out], env=USER_ENV, text=True, capture_output=True, timeout=300)
    assert r.returncode == 0, r.stderr[-3000:]


@pytest.mark.slow
def test_train_with_threads_option_interrupted_at_a_random_step_resumes_bit_identically(user_toy, tmp_path):
    """SIGINT at a random step past the first validation (the step is drawn from a fresh seed each run and
    printed, so a failure can be replayed), then the same command: every tensor of the final weights equals
    an uninterrupted run's, bit for bit."""
    straight = tmp_path / "straight"
    run_user_train(user_toy, straight)
    seed = random.SystemRandom().randrange(1 << 30)
    stop_at = random.Random(seed).randrange(55, USER_STEPS - 10)
    run = tmp_path / "run"
    proc = subprocess.Popen([sys.executable, "-m", "roomlight.cli.main", *map(str, USER_TRAIN), "--data", user_toy,
                             "--out", run], env=USER_ENV, text=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    t_end = time.monotonic() + 240
    while max(train_steps(run), default=0) < stop_at:
        assert proc.poll() is None, f"seed {seed}: finished before step {stop_at}: {proc.stderr.read()[-2000:]}"
        assert time.monotonic() < t_end, f"seed {seed}: never reached step {stop_at}"
        time.sleep(0.005)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 128 + signal.SIGINT, f"seed {seed}: {err[-2000:]}"
    stopped = max(train_steps(run))
    assert stop_at <= stopped < USER_STEPS, f"seed {seed}"
    run_user_train(user_toy, run)
    a, b = final_weights(run, USER_STEPS), final_weights(straight, USER_STEPS)
    assert a.keys() == b.keys()
    differing = {k: float((a[k] - b[k]).abs().max()) for k in a if not bool((a[k] == b[k]).all())}
    assert not differing, f"seed {seed} (stopped at step {stopped}): {len(differing)} tensors differ, largest " \
                          f"{max(differing.values()):.3g}"


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_sigint_and_sigterm_are_both_deferred_to_the_end_of_the_step(sig):
    """The training loops' handler: the first signal only records itself, a second one stops at once
    (not at a step boundary), and the previous handlers come back afterwards."""
    from roomlight.prior.train.interrupt import Interrupted, deferred_interrupts

    before = signal.getsignal(sig)
    notes = []
    with deferred_interrupts(notes.append) as flag:
        os.kill(os.getpid(), sig)
        time.sleep(0.05)  # the handler runs between bytecodes of the main thread
        assert flag.signum == sig and len(notes) == 1 and signal.Signals(sig).name in notes[0]
        with pytest.raises(Interrupted) as stopped:
            os.kill(os.getpid(), sig)
            time.sleep(1.0)
        assert stopped.value.signum == sig and not stopped.value.clean
    assert signal.getsignal(sig) is before


# ----------------------------------------------------------------------------- synth, bench make, bench run
# synth and bench install no handler of their own: SIGINT raises KeyboardInterrupt (the graceful path),
# SIGTERM and SIGKILL end the process where it stands, so SIGKILL (which no code can intercept) stands
# for both: every write must be atomic. Each command is interrupted both ways in one sequence (Ctrl-C,
# then SIGKILL on the re-run, then the re-run to the end), which also checks that a run resumed once
# can be stopped and resumed again.


def finished_exrs(root: Path, pattern: str) -> list[Path]:
    """Every EXR under ``root`` matching ``pattern`` that is not a partial or hidden temporary file."""
    return [p for p in sorted(root.glob(pattern)) if ".partial" not in p.name and not p.name.startswith(".")]


def exr_pixels(root: Path, pattern: str) -> dict:
    """{relative path: {channel: array}} of every finished EXR under ``root``."""
    from roomlight.core.io import read_exr

    return {p.relative_to(root).as_posix(): read_exr(p) for p in finished_exrs(root, pattern)}


def assert_same_exrs(a: dict, b: dict) -> None:
    assert sorted(a) == sorted(b), "lost or extra files"
    for name in a:
        for ch in a[name]:
            assert (a[name][ch] == b[name][ch]).all(), f"{name} channel {ch} differs"


def interrupt_twice_and_rerun(args, out: Path, count, seed: int, max_delay: float = 1.0, attempts: int = 3):
    """Ctrl-C ``roomlight ARGS`` after its first finished item, SIGKILL the re-run after it has finished
    one more, then re-run it to completion (each signal after a random delay, see :func:`kill_when`).

    ``count()`` is the number of finished items under ``out``. On a fast machine the command may finish
    before a signal, or the signal may land while the interpreter is already shutting down after the last
    item was written (Python then ignores it and the command exits 0): such a run tested nothing, so the
    test starts over on an empty folder with the signals sent as soon as their item appears, at most
    ``attempts`` times.
    """
    for attempt in range(attempts):
        delay = max_delay if attempt == 0 else 0.0
        code, err = kill_when(args, lambda: count() >= 1, signal.SIGINT, seed=seed, max_delay=delay)
        if code != 0:
            assert "Traceback" not in err, err[-2000:]  # Ctrl-C ends in one line, not a stack trace
            done = count()
            code, _ = kill_when(args, lambda: count() > done, signal.SIGKILL, seed=seed + 1, max_delay=delay)
            if code != 0:
                break
        shutil.rmtree(out)
    assert code != 0, f"the command finished before its signals in every one of {attempts} attempts"
    roomlight(*args)


# Eight rooms and a delay under 0.3 s: with three rooms and up to 1 s, a quiet machine (0.2 s a room)
# finished the last two within the delay, and the signal reached a process that had done its work.
SYNTH = ["synth", "--n", 8, "--res", "16x32", "--spp", 4, "--no-denoise", "--workers", 1, "--no-summary"]


@pytest.fixture(scope="module")
def synth_straight(tmp_path_factory):
    out = tmp_path_factory.mktemp("synth") / "rooms"
    roomlight(*SYNTH, "--out", out)
    return exr_pixels(out, "**/*.exr")


@pytest.mark.slow
@pytest.mark.mitsuba
def test_synth_interrupted_then_rerun_renders_every_room_once_and_identically(synth_straight, tmp_path):
    out = tmp_path / "rooms"
    interrupt_twice_and_rerun([*SYNTH, "--out", out], out, lambda: len(finished_exrs(out, "**/*.exr")), seed=2,
                              max_delay=0.3)
    assert_same_exrs(exr_pixels(out, "**/*.exr"), synth_straight)
    assert not list(out.glob("**/*.partial.exr")), "a partial file was left behind"


def bench_make_args(panos, out):
    return ["bench", "make", "--panos", panos, "--out", out, "--n", 6, "--emitter-res", 16, "--res", "16x16",
            "--spp", 4, "--materials", "diffuse", "--quiet"]


@pytest.fixture(scope="module")
def bench_straight(toy, tmp_path_factory):
    out = tmp_path_factory.mktemp("bench") / "bench"
    roomlight(*bench_make_args(toy, out))
    return out


def manifest_scenes(bench: Path) -> list:
    return [s["id"] for s in json.loads((bench / "manifest.json").read_text())["scenes"]]


@pytest.mark.slow
@pytest.mark.mitsuba
def test_bench_make_interrupted_then_rerun_builds_every_scene_once_and_identically(toy, bench_straight, tmp_path):
    out = tmp_path / "bench"
    # Six scenes and a delay of at most 0.3 s after each item: on a fast, quiet machine two scenes
    # and a 1 s delay let the command finish before the signal.
    interrupt_twice_and_rerun(bench_make_args(toy, out), out, lambda: len(list(out.glob("*/panorama.json"))),
                              seed=102, max_delay=0.3)
    assert manifest_scenes(out) == manifest_scenes(bench_straight)
    assert len(set(manifest_scenes(out))) == 6
    assert_same_exrs(exr_pixels(out, "*/*/*.exr"), exr_pixels(bench_straight, "*/*/*.exr"))


RUN = ["--methods", "direct-envmap", "--preset", "fast", "--iterations", 3, "--fit-spp", 2, "--eval-spp", 4,
       "--quiet"]


def results(out: Path) -> dict:
    """{case: scores} of every finished case (timings left out)."""
    found = {}
    for p in sorted(out.glob("cases/*/*/*/result.json")):  # fit/result.json is the fit's own
        rec = json.loads(p.read_text())
        found[p.parent.relative_to(out).as_posix()] = json.dumps(rec.get("metrics", rec.get("scores")), sort_keys=True)
    return found


@pytest.fixture(scope="module")
def run_straight(bench_straight, tmp_path_factory):
    out = tmp_path_factory.mktemp("run") / "results"
    roomlight("bench", "run", bench_straight, "--out", out, *RUN)
    return results(out)


@pytest.mark.slow
@pytest.mark.mitsuba
def test_bench_run_interrupted_then_rerun_runs_every_case_once_and_identically(bench_straight, run_straight, tmp_path):
    out = tmp_path / "results"
    interrupt_twice_and_rerun(["bench", "run", bench_straight, "--out", out, *RUN], out,
                              lambda: len(list(out.glob("cases/*/*/*/result.json"))), seed=202)
    assert len(run_straight) == 6
    assert results(out) == run_straight
