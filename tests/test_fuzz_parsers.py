"""Property-based fuzzing of the parsers of files roomlight reads: scene descriptions and settings.

Whatever JSON a user writes, parsing either succeeds or raises :class:`RoomlightError` (which the
command line prints as one line); never a TypeError, KeyError, ValueError or AttributeError from
deep inside. Valid settings survive a round trip through their JSON form unchanged.
"""

from __future__ import annotations

import copy
import json
from pathlib import Path

import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

from roomlight.evaluation.bench.builder import BenchConfig  # noqa: E402
from roomlight.errors import RoomlightError  # noqa: E402
from roomlight.prior.latent_fit import LatentFitConfig  # noqa: E402
from roomlight.fitting.inverse.config import FitConfig  # noqa: E402
from roomlight.prior.losses import LossConfig  # noqa: E402
from roomlight.prior.model import ModelConfig  # noqa: E402
from roomlight.fitting.scene.description import parse_scene  # noqa: E402
from roomlight.prior.train.config import TrainConfig  # noqa: E402

FUZZ = settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])

json_scalars = st.one_of(st.none(), st.booleans(), st.integers(-10**20, 10**20),
                         st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=8))
json_values = st.recursive(json_scalars, lambda inner: st.one_of(
    st.lists(inner, max_size=4), st.dictionaries(st.text(max_size=8), inner, max_size=4)), max_leaves=12)

VALID_SCENE = {
    "version": 1,
    "objects": [{"id": "a", "shape": "knot", "translate": [0, 0, -2], "scale": 0.5, "rotate": [0, 1, 0, 30],
                 "material": {"type": "principled", "base_color": [0.5, 0.4, 0.3], "roughness": 0.3}},
                {"id": "b", "shape": "spiky", "material": "mirror"}],
    "views": {"input": {"camera": {"origin": [0, 0, 0], "target": [0, 0, -1], "up": [0, 1, 0], "fov": 60,
                                   "width": 16, "height": 12}, "objects": ["a", "b"]}},
    "metadata": {"note": "fuzz"},
}


def _paths(d, prefix=()):
    """Every (path, value) inside nested dicts and lists."""
    yield prefix, d
    if isinstance(d, dict):
        for k, v in d.items():
            yield from _paths(v, prefix + (k,))
    elif isinstance(d, list):
        for i, v in enumerate(d):
            yield from _paths(v, prefix + (i,))


SCENE_PATHS = [p for p, _ in _paths(VALID_SCENE) if p]


def _set(d, path, value):
    for key in path[:-1]:
        d = d[key]
    d[path[-1]] = value


def _parse(data):
    try:
        return parse_scene(data, Path("."), where="scene.json")
    except RoomlightError:
        return None


def test_the_valid_scene_parses():
    scene = parse_scene(copy.deepcopy(VALID_SCENE), Path("."))
    assert scene.views["input"].camera.width == 16 and scene.objects["a"].scale == 0.5


@FUZZ
@given(json_values)
def test_any_json_document_is_a_scene_or_one_scene_error(data):
    _parse(data)


@FUZZ
@given(st.sampled_from(SCENE_PATHS), json_values)
def test_any_field_replaced_by_any_value_gives_a_scene_or_one_scene_error(path, value):
    data = copy.deepcopy(VALID_SCENE)
    _set(data, path, value)
    _parse(data)


@FUZZ
@given(st.sampled_from([p for p, v in _paths(VALID_SCENE) if isinstance(v, dict)]), st.text(min_size=1, max_size=10),
       json_values)
def test_an_added_unknown_field_is_refused_by_its_path(path, key, value):
    data = copy.deepcopy(VALID_SCENE)
    target = data
    for k in path:
        target = target[k]
    # entries of "views" are view names and "metadata" is free-form: neither has fixed fields
    if key in target or (path and path[0] == "metadata") or (path and path[-1] == "views"):
        return
    target[key] = value
    with pytest.raises(RoomlightError, match="unknown field") as e:
        parse_scene(data, Path("."), where="scene.json")
    assert ".".join(["scene.json", *map(str, path)]).replace(".0", "[0]").replace(".1", "[1]") in str(e.value)


SETTINGS = [ModelConfig, TrainConfig, LossConfig, FitConfig, LatentFitConfig, BenchConfig]


@FUZZ
@given(st.sampled_from(SETTINGS), st.dictionaries(st.text(max_size=12), json_values, max_size=4))
def test_any_mapping_is_settings_or_one_roomlight_error(cls, data):
    try:
        cls.from_dict(data)
    except RoomlightError:
        pass


@FUZZ
@given(st.sampled_from(SETTINGS), st.data())
def test_any_field_with_any_value_is_settings_or_one_roomlight_error(cls, data):
    d = cls().to_dict()
    name = data.draw(st.sampled_from(sorted(d)))
    d[name] = data.draw(json_values)
    try:
        cfg = cls.from_dict(d)
    except RoomlightError:
        return
    again = cls.from_dict(json.loads(json.dumps(cfg.to_dict())))
    assert json.dumps(again.to_dict()) == json.dumps(cfg.to_dict())  # NaN-safe equality


@pytest.mark.parametrize("cls", SETTINGS)
def test_settings_round_trip_through_json(cls):
    cfg = cls()
    assert cls.from_dict(json.loads(json.dumps(cfg.to_dict()))) == cfg
