"""The method registry: each record says what the code that uses it does."""

from __future__ import annotations

import pytest

from roomlight.errors import RoomlightError
from roomlight.fitting.methods import FIT, PHOTO, METHODS, default_run, is_reference, method, methods_for, needs_prior

from helpers_prior import tiny_prior
from helpers_scene import make_tiny_scene


@pytest.mark.mitsuba
def test_each_scene_method_builds_the_light_its_record_names(tmp_path):
    """``make_light`` is the code that acts on the record: its light's kind must be the record's."""
    from roomlight.fitting.inverse import FitConfig, make_light

    scene, _, _ = make_tiny_scene(tmp_path, height=8, res=16, spp=4)
    prior = tiny_prior()
    for name in methods_for(FIT, fitted=True):
        light = make_light(name, scene, FitConfig(), model=prior)
        want = method(name).light
        assert light.kind == want or (want == "sphere" and light.kind.startswith("sphere:")), name
        assert hasattr(light, "z") == needs_prior(name), name  # a latent exactly for the prior methods


def test_the_paper_s_table_rows_and_the_benchmarks_defaults():
    # Table 2 of the paper: smoothness baselines (env map, sphere proxy, 2.5D AL), then the priors.
    order = [m.name for m in METHODS]
    paper = ["direct-envmap", "direct-sphere", "direct-al", "prior-envmap", "prior"]
    assert [m for m in order if m in paper] == paper
    # the floor (no light at all) opens the table, what uses the truth closes it
    fitted = [order.index(m.name) for m in METHODS if not m.is_reference]
    assert order[0] == "naive-paste" and order.index("naive-paste") < min(fitted)
    assert max(fitted) < min(order.index(m.name) for m in METHODS if m.source.startswith("truth"))
    # Without --methods: the paper's five on scenes, prior and the env-map baselines on photos; never a VENI
    # row (they load models of their own) and never a reference.
    assert set(default_run(FIT)) == set(paper)
    assert set(default_run(PHOTO)) == {"prior", "prior-envmap", "direct-envmap"}
    assert default_run(FIT)[0] == default_run(PHOTO)[0] == "prior"
    assert {"oracle", "oracle-envmap", "prior-ceiling", "naive-paste"} == set(methods_for(PHOTO, fitted=False))
    assert all(is_reference(m) for m in ("oracle", "oracle-envmap", "prior-ceiling", "naive-paste"))
    assert not is_reference("prior") and not is_reference("not-a-method")


def test_start_variants_fit_the_prior_from_a_fixed_start():
    for name, init in (("prior-view", "view"), ("prior-samples", "samples"), ("prior-zero", "zero")):
        m = method(name)
        assert (m.fitted_as, m.init, m.light, m.runs) == ("prior", init, "mesh", frozenset({PHOTO}))
    assert method("prior").fitted_as == "prior" and method("prior").init is None


def test_which_methods_load_the_command_s_model():
    assert method("prior").takes_model_option(False) and method("prior-envmap").takes_model_option(False)
    assert not method("veni").takes_model_option(False)       # loaded by name (--set veni_model=)
    assert method("veni-d").takes_model_option(True)          # unless --model gives one
    assert not method("direct-al").takes_model_option(True)


def test_an_unknown_name_gets_one_line_naming_the_known_ones():
    with pytest.raises(RoomlightError, match=r"unknown method 'nope'; choose one of naive-paste, constant-colour, "):
        method("nope")
