"""Every command against broken inputs made on the fly: one clear line, exit code 2, nothing half-written.

A corpus of broken files (truncated, wrong magic, empty, NaN/inf, negative, zero, wrong aspect,
size mismatch, wrong types and unknown names in each file roomlight reads, empty folders) is
crossed with the commands that read each kind of file. Every case must end with exit code 2,
exactly one line on stderr that starts with ``error:`` and names the broken file (or folder), no
traceback, and no output folder left behind.
"""

from __future__ import annotations

import json
import re
import shutil

import numpy as np
import pytest
from click.testing import CliRunner

from roomlight.cli.main import cli
from roomlight.core.examples import example_room
from roomlight.core.io import write_exr, write_panorama
from roomlight.prior.model import PanoVAE, get_preset
from roomlight.prior.model.normalization import Normalization

pytestmark = pytest.mark.usefixtures("one_torch_thread")


# ----------------------------------------------------------------------------- the corpus
def _good_arrays(h=16):
    rad, dep = example_room(h)
    return rad.numpy().copy(), dep.numpy().copy()


def _pano(path, rad, dep):
    write_panorama(path, (rad, dep), half=False)
    return path


def _raw_pano(path, rad, dep):
    """R, G, B, Z channels as given: write_panorama itself refuses what the corpus needs."""
    write_exr(path, {"R": rad[..., 0], "G": rad[..., 1], "B": rad[..., 2], "Z": dep})
    return path


def _edited(path, edit):
    rad, dep = _good_arrays()
    edit(rad, dep)
    return _pano(path, rad, dep)


def _truncated(path):
    _pano(path, *_good_arrays())
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 3])
    return path


PANORAMAS = {
    "truncated": _truncated,
    "wrong-magic": lambda p: (p.write_bytes(b"GIF89a" + bytes(range(256)) * 8), p)[1],
    "empty": lambda p: (p.write_bytes(b""), p)[1],
    "nan": lambda p: _edited(p, lambda r, d: r.__setitem__((2, 3, 0), np.nan)),
    "inf": lambda p: _edited(p, lambda r, d: r.__setitem__((5, 7, 2), np.inf)),
    "negative-radiance": lambda p: _edited(p, lambda r, d: r.__setitem__((4, 4, 1), -0.25)),
    "zero-depth": lambda p: _edited(p, lambda r, d: d.__setitem__((6, 6), 0.0)),
    "negative-depth": lambda p: _edited(p, lambda r, d: d.__setitem__((6, 9), -1.0)),
    "wrong-aspect": lambda p: _raw_pano(p, *(a[:, :16] for a in _good_arrays())),
    "no-depth": lambda p: (write_exr(p, {c: _good_arrays()[0][..., i] for i, c in enumerate("RGB")}), p)[1],
}


@pytest.fixture(scope="module")
def workspace(tmp_path_factory):
    root = tmp_path_factory.mktemp("bad-inputs")
    good = _pano(root / "good.exr", *_good_arrays())
    model = root / "model"
    rad, dep = _good_arrays()
    norm = Normalization.from_data([(torch_chw(rad), torch_chw(dep[..., None]))])
    PanoVAE(get_preset("tiny"), norm).save_pretrained(model)
    scene = root / "scenes" / "scene.json"
    scene.parent.mkdir()
    scene.write_text(json.dumps(SCENE))
    return {"root": root, "good": good, "model": model, "scene": scene}


def torch_chw(a):
    import torch

    return torch.from_numpy(np.ascontiguousarray(a.transpose(2, 0, 1)))


def run(args, tmp_path):
    result = CliRunner().invoke(cli, [str(a) for a in args])
    result.command_options = _options(args)
    return result


def _options(args) -> set:
    """The options of the (sub)command ``args`` runs."""
    cmd = cli
    for a in args:
        sub = cmd.get_command(None, str(a)) if hasattr(cmd, "get_command") else None
        if sub is None:
            break
        cmd = sub
    return {o for p in cmd.params for o in p.opts}


def assert_one_clean_line(result, named: str, out=None):
    assert result.exit_code == 2, (result.exit_code, result.output, result.exception)
    assert not isinstance(result.exception, Exception) or isinstance(result.exception, SystemExit), \
        f"traceback: {result.exception!r}"
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    errors = [line for line in lines if line.startswith("error:")]
    assert len(errors) == 1 and lines[-1] == errors[0], result.stderr
    assert "Traceback" not in result.output
    assert named in errors[0], f"{named!r} not named in {errors[0]!r}"
    suggested = set(re.findall(r"(?<![\w-])--[a-z][a-z-]+", errors[0]))
    assert suggested <= result.command_options, f"suggests {suggested - result.command_options}, not options here"
    if out is not None:
        assert not out.exists() or not any(out.iterdir()), f"half-written output in {out}"


# ----------------------------------------------------------------------------- panoramas
PANORAMA_COMMANDS = {
    "emitter": lambda w, bad, out: ["emitter", bad, "--out", out],
    "fit-pano": lambda w, bad, out: ["fit-pano", "--model", w["model"], bad, "--steps", 2, "--out", out],
    "sample --interpolate": lambda w, bad, out: ["sample", "--model", w["model"], "--interpolate", bad, w["good"],
                                                 "--n", 2, "--no-render", "--no-emitters", "--out", out],
    "bench make": lambda w, bad, out: ["bench", "make", "--panos", bad, "--out", out, "--n", 1, "--quiet"],
}
# fit-pano and sample fit radiance alone when there is no depth; the others need it.
NEEDS_DEPTH = {"emitter", "bench make", "sample --interpolate"}


# A panorama without depth is a bad input only for the commands that need depth.
BROKEN_PANORAMA_CASES = [(command, kind) for command in sorted(PANORAMA_COMMANDS) for kind in sorted(PANORAMAS)
                         if kind != "no-depth" or command in NEEDS_DEPTH]


@pytest.mark.parametrize(("command", "kind"), BROKEN_PANORAMA_CASES)
def test_broken_panorama(workspace, tmp_path, command, kind):
    bad = PANORAMAS[kind](tmp_path / f"broken-{kind}.exr")
    out = tmp_path / "out"
    r = run(PANORAMA_COMMANDS[command](workspace, bad, out), tmp_path)
    assert_one_clean_line(r, bad.name, out)


def test_depth_of_another_size(workspace, tmp_path):
    rad, _ = _good_arrays()
    write_exr(tmp_path / "rgb.exr", {c: rad[..., i] for i, c in enumerate("RGB")})
    np.save(tmp_path / "depth.npy", np.ones((8, 16), np.float32))
    r = run(["emitter", tmp_path / "rgb.exr", "--depth", tmp_path / "depth.npy", "--out", tmp_path / "out"], tmp_path)
    assert_one_clean_line(r, "depth.npy", tmp_path / "out")


# ----------------------------------------------------------------------------- folders of panoramas
FOLDER_COMMANDS = {
    "train": lambda w, d, out: ["train", "--data", d, "--out", out, "--config", "tiny", "--max-steps", 2, "--no-cache"],
    "data stats": lambda w, d, out: ["data", "stats", d, "--config", "tiny", "--out", out / "stats.json"],
    "eval-prior": lambda w, d, out: ["eval-prior", "--model", w["model"], "--data", d, "--fit-steps", 0, "--out", out],
    "bench make": lambda w, d, out: ["bench", "make", "--panos", d, "--out", out, "--quiet"],
    "train-view-encoder": lambda w, d, out: ["train-view-encoder", "--data", d, "--out", out, "--model", w["model"],
                                             "--max-steps", 2],
}


@pytest.mark.parametrize("content", ["empty", "not-an-exr"])
@pytest.mark.parametrize("command", sorted(FOLDER_COMMANDS))
def test_folder_without_a_usable_panorama(workspace, tmp_path, command, content):
    data = tmp_path / "data"
    data.mkdir()
    if content == "not-an-exr":
        (data / "notes.exr").write_text("not an image\n")
    out = tmp_path / "out"
    r = run(FOLDER_COMMANDS[command](workspace, data, out), tmp_path)
    assert_one_clean_line(r, str(data), out)
    if content == "not-an-exr" and command in ("train", "data stats", "eval-prior", "train-view-encoder"):
        assert "notes.exr" in r.output  # each skipped file is named with its reason first
        assert "no usable panorama in" in r.stderr


# ----------------------------------------------------------------------------- model checkpoints
def _model_copy(workspace, tmp_path):
    d = tmp_path / "broken-model"
    shutil.copytree(workspace["model"], d)
    return d


def _config_edit(edit):
    def make(workspace, tmp_path):
        d = _model_copy(workspace, tmp_path)
        meta = json.loads((d / "config.json").read_text())
        edit(meta)
        (d / "config.json").write_text(json.dumps(meta))
        return d, "config.json"
    return make


def _weights_edit(edit):
    def make(workspace, tmp_path):
        d = _model_copy(workspace, tmp_path)
        w = d / "model.safetensors"
        w.write_bytes(edit(w.read_bytes()))
        return d, "model.safetensors"
    return make


MODEL_FIELDS = {"resolution": "16x32", "latent_dim": "16", "ch": "32", "ch_mult": 2, "num_res_blocks": 1.5,
                "z_channels": None, "norm_groups": True, "in_channels": [4], "logvar_range": "wide", "norm_eps": "1e-6"}
MODELS = {
    "weights-truncated": _weights_edit(lambda b: b[: len(b) // 2]),
    "weights-empty": _weights_edit(lambda b: b""),
    "weights-wrong-magic": _weights_edit(lambda b: b"\x89PNG\r\n" + b[6:]),
    "weights-one-byte-changed": _weights_edit(lambda b: b[:-9] + bytes([b[-9] ^ 1]) + b[-8:]),
    "config-not-json": lambda w, t: ((_model_copy(w, t) / "config.json").write_text("{model: tiny"), (t / "broken-model", "config.json"))[1],
    "config-unknown-top-level": _config_edit(lambda m: m.update(wieghts_sha256="0")),
    "config-unknown-model-field": _config_edit(lambda m: m["model"].update(latent_dims=16)),
    **{f"config-{k}-wrong-type": _config_edit(lambda m, k=k, v=v: m["model"].update({k: v}))
       for k, v in MODEL_FIELDS.items()},
}
MODEL_COMMANDS = {
    "fit-pano": lambda w, m, out: ["fit-pano", "--model", m, w["good"], "--steps", 2, "--out", out],
    "sample": lambda w, m, out: ["sample", "--model", m, "--n", 1, "--no-render", "--no-emitters", "--out", out],
    "eval-prior": lambda w, m, out: ["eval-prior", "--model", m, "--data", w["root"], "--fit-steps", 0,
                                     "--out", out],
    "fit": lambda w, m, out: ["fit", w["scene"], "--method", "prior", "--model", m, "--out", out],
}


@pytest.mark.parametrize("kind", sorted(MODELS))
@pytest.mark.parametrize("command", sorted(MODEL_COMMANDS))
def test_broken_checkpoint(workspace, tmp_path, command, kind):
    model, name = MODELS[kind](workspace, tmp_path)
    out = tmp_path / "out"
    r = run(MODEL_COMMANDS[command](workspace, model, out), tmp_path)
    assert_one_clean_line(r, name, out)
    if kind.endswith("wrong-type"):
        field = kind[len("config-"):-len("-wrong-type")]
        assert re.search(rf"model\.{field}(\[\d\])?: expected", r.stderr), r.stderr
    if kind.startswith("config-unknown"):
        assert "did you mean" in r.stderr


# ----------------------------------------------------------------------------- scene files
SCENE = {"objects": [{"id": "a", "shape": "knot", "material": {"type": "diffuse", "reflectance": [0.5, 0.5, 0.5]}}],
         "views": {"input": {"camera": {"width": 8, "height": 8, "fov": 60}, "objects": ["a"]}}}


def _scene_edit(edit):
    def make(path):
        d = json.loads(json.dumps(SCENE))
        edit(d)
        path.write_text(json.dumps(d))
        return path
    return make


SCENES = {
    "unknown-top-level": (_scene_edit(lambda d: d.update(lights=[])), None),
    "unknown-camera-field": (_scene_edit(lambda d: d["views"]["input"]["camera"].update(fov_deg=50)), "'fov'"),
    "unknown-material-field": (_scene_edit(lambda d: d["objects"][0]["material"].update(colour=[1, 0, 0])), None),
    "unknown-object-field": (_scene_edit(lambda d: d["objects"][0].update(translation=[0, 0, -2])), "'translate'"),
    "width-as-string": (_scene_edit(lambda d: d["views"]["input"]["camera"].update(width="8")), None),
    "fov-as-string": (_scene_edit(lambda d: d["views"]["input"]["camera"].update(fov="60")), None),
    "views-as-list": (_scene_edit(lambda d: d.update(views=[1, 2])), None),
    "not-json": (lambda p: (p.write_text("{objects: ["), p)[1], None),
    "empty": (lambda p: (p.write_text(""), p)[1], None),
}


@pytest.mark.parametrize("kind", sorted(SCENES))
def test_broken_scene_file(tmp_path, kind):
    make, suggestion = SCENES[kind]
    scene = make(tmp_path / f"broken-{kind}.json")
    out = tmp_path / "out"
    r = run(["fit", scene, "--method", "direct-envmap", "--preset", "fast", "--out", out], tmp_path)
    assert_one_clean_line(r, scene.name, out)
    if suggestion:
        assert f"did you mean {suggestion}" in r.stderr


def test_exr_given_as_scene_file(workspace, tmp_path):
    r = run(["fit", workspace["good"], "--method", "direct-envmap", "--out", tmp_path / "out"], tmp_path)
    assert_one_clean_line(r, "good.exr", tmp_path / "out")
    assert "expected a scene description" in r.stderr


# ----------------------------------------------------------------------------- benchmark manifests and settings
MANIFESTS = {
    "unknown-key": lambda m: m.update(scene=[]),
    "scene-unknown-key": lambda m: m["scenes"][0].update(materials="matte"),
    "scene-wrong-type": lambda m: m["scenes"][0].update(scene=3),
    "config-wrong-type": lambda m: m["config"].update(spp="many"),
}


@pytest.mark.parametrize("kind", sorted(MANIFESTS) + ["not-json", "missing"])
def test_broken_benchmark_manifest(tmp_path, kind):
    bench = tmp_path / "bench"
    bench.mkdir()
    m = {"version": 1, "config": {"n": 1}, "panoramas": [],
         "scenes": [{"id": "x/matte", "panorama": "x", "material": "matte", "scene": "x/matte/scene.json"}]}
    if kind in MANIFESTS:
        MANIFESTS[kind](m)
        (bench / "manifest.json").write_text(json.dumps(m))
    elif kind == "not-json":
        (bench / "manifest.json").write_text("{")
    r = run(["bench", "run", bench, "--out", tmp_path / "out", "--methods", "direct-envmap"], tmp_path)
    assert_one_clean_line(r, "manifest.json", tmp_path / "out")


@pytest.mark.parametrize("setting, named, hint", [
    ("batchsize=4", "batchsize", "did you mean 'batch_size'"),
    ('batch_size="4"', "batch_size", "expected int"),
    ("loss.peek=0", "peek", "did you mean 'peak'"),
    ("loss.kl_beta=[1]", "kl_beta", "expected float"),
    ("aug_roll=3", "aug_roll", "expected bool"),
])
def test_wrongly_typed_or_unknown_training_settings(workspace, tmp_path, setting, named, hint):
    data = tmp_path / "data"
    data.mkdir()
    shutil.copy(workspace["good"], data / "a.exr")
    r = run(["train", "--data", data, "--out", tmp_path / "run", "--config", "tiny", "--set", setting], tmp_path)
    assert_one_clean_line(r, named)
    assert hint in r.stderr
    assert not (tmp_path / "run").exists()


@pytest.mark.parametrize("kind", ["truncated", "wrong-magic", "nan"])
def test_a_real_process_prints_one_line_and_nothing_else(tmp_path, kind):
    """The C libraries behind the readers write their own complaints to the terminal; a real
    process (not the in-process runner above) must still show only roomlight's line."""
    import os
    import subprocess
    import sys
    from pathlib import Path

    bad = PANORAMAS[kind](tmp_path / f"broken-{kind}.exr")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(Path(__file__).parents[1] / "src"),
                                                         os.environ.get("PYTHONPATH", "")])}
    r = subprocess.run([sys.executable, "-m", "roomlight.cli.main", "emitter", str(bad), "--out", str(tmp_path / "o")],
                       env=env, capture_output=True, text=True, timeout=300)
    assert r.returncode == 2 and r.stdout == ""
    assert len(r.stderr.splitlines()) == 1 and r.stderr.startswith("error: ") and bad.name in r.stderr, r.stderr


def _wrong_value(default):
    """A JSON value of another type than the field's default."""
    if isinstance(default, bool):
        return 3
    if isinstance(default, (int, float)):
        return "x"
    if isinstance(default, str):
        return 5
    return True  # a list, a mapping or None


def _train_fields():
    from dataclasses import fields

    from roomlight.prior.train.config import TrainConfig

    cfg = TrainConfig()
    return [(f.name, _wrong_value(getattr(cfg, f.name))) for f in fields(TrainConfig)]


@pytest.mark.parametrize("field, value", _train_fields(), ids=[f for f, _ in _train_fields()])
def test_every_training_setting_refuses_a_wrong_type_by_name(tmp_path, field, value):
    data = tmp_path / "data"
    data.mkdir()
    r = run(["train", "--data", data, "--out", tmp_path / "run", "--config", "tiny", "--set",
             f"{field}={json.dumps(value)}"], tmp_path)
    assert_one_clean_line(r, f"TrainConfig.{field}: expected")
    assert not (tmp_path / "run").exists()


def _bench_fields():
    from dataclasses import fields

    from roomlight.evaluation.bench.builder import BenchConfig

    cfg = BenchConfig()
    return [(f.name, _wrong_value(getattr(cfg, f.name))) for f in fields(BenchConfig)]


@pytest.mark.parametrize("field, value", _bench_fields(), ids=[f for f, _ in _bench_fields()])
def test_every_benchmark_setting_in_a_manifest_refuses_a_wrong_type_by_path(tmp_path, field, value):
    bench = tmp_path / "bench"
    bench.mkdir()
    (bench / "manifest.json").write_text(json.dumps({"version": 1, "config": {field: value}, "scenes": []}))
    r = run(["bench", "run", bench, "--out", tmp_path / "out", "--methods", "direct-envmap"], tmp_path)
    assert_one_clean_line(r, "manifest.json", tmp_path / "out")
    assert f"manifest.config.{field}: expected" in r.stderr
