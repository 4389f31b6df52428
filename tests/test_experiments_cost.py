"""The cost table: what it measures, its arithmetic, and that a rerun reuses finished parts."""

import json

import pytest
from click.testing import CliRunner

from roomlight.cli.main import cli
from roomlight.errors import RoomlightError
from roomlight.evaluation.experiments import cost as cost_mod
from roomlight.evaluation.experiments.cost import COST_PRESETS, PAPER_SCHEDULE, CostConfig, median_seconds


def test_median_seconds_times_each_call_after_a_warm_up(monkeypatch):
    clock = iter([0.0, 1.0, 10.0, 13.0, 20.0, 22.0])  # three timed calls: 1, 3 and 2 seconds
    monkeypatch.setattr(cost_mod.time, "perf_counter", lambda: next(clock))
    calls = []
    assert median_seconds(lambda: calls.append(1), 3) == 2.0
    assert len(calls) == 4  # the warm-up call is not timed


def test_settings_are_checked():
    with pytest.raises(RoomlightError, match="unknown method"):
        CostConfig(methods=("prior", "dpi"))
    with pytest.raises(RoomlightError, match="unknown model preset"):
        CostConfig(model_preset="huge")


@pytest.mark.mitsuba
def test_quick_cost_table_on_the_tiny_network(tmp_path, one_torch_thread):
    out = tmp_path / "cost"
    args = ["experiment", "cost", "--out", out, "--quick", "--model-preset", "tiny", "--device", "cpu",
            "--methods", "prior,direct-envmap"]
    r = CliRunner().invoke(cli, [str(a) for a in args], catch_exceptions=False)
    assert r.exit_code == 0, r.output
    doc = json.loads((out / "cost.json").read_text())
    m = doc["model"]
    assert m["parameters"] == 21_624  # the tiny preset (docs/training.md)
    epochs, n, batch = PAPER_SCHEDULE
    assert m["paper_schedule_panoramas"] == epochs * (n // batch) * batch == 662_400
    assert m["paper_schedule_hours"] == pytest.approx(662_400 / m["panoramas_per_second"] / 3600)
    assert m["panoramas_per_second"] == pytest.approx(COST_PRESETS["quick"].train_batch / m["train_step_seconds"])
    steps = 662_400 / COST_PRESETS["quick"].train_batch
    assert m["paper_schedule_cpu_hours"] == pytest.approx(steps * m["train_step_cpu_seconds"] / 3600)
    for method in ("prior", "direct-envmap"):
        f = doc["fits"][method]
        assert f["fit_minutes"] == pytest.approx(f["seconds_per_iteration"] * 500 / 60)
        assert f["fit_cpu_minutes"] == pytest.approx(f["cpu_seconds_per_iteration"] * 500 / 60)
        assert f["iterations_timed"] == COST_PRESETS["quick"].fit_iterations
    md = (out / "cost.md").read_text()
    assert doc["device"]["name"] in md and "| roomlight prior | 2.5D AL | 0.0216 |" in md
    assert (out / "figures" / "cost.png").is_file()
    # a rerun measures nothing again
    parts = {p: p.stat().st_mtime_ns for p in (out / "parts").glob("*.json")}
    r = CliRunner().invoke(cli, [str(a) for a in args], catch_exceptions=False)
    assert r.exit_code == 0
    assert parts == {p: p.stat().st_mtime_ns for p in (out / "parts").glob("*.json")}
    assert json.loads((out / "cost.json").read_text())["model"] == m
