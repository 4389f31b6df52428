"""Paired comparison of two eval-prior reports (roomlight.prior.eval.compare, scripts/compare_prior_evals.py)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from roomlight.errors import RoomlightError
from roomlight.prior.eval.compare import compare_reports, comparison_markdown


def _report(rows: dict[str, dict[str, dict]]) -> dict:
    """A report with per-image values: rows = {name: {row: {metric: value}}}."""
    return {"per_image": [{"name": n, **r} for n, r in rows.items()]}


BASE = _report({
    "a.exr": {"latent fit": {"psnr_ldr": 20.0, "peak_stops": 1.0, "abs_rel": 0.06}},
    "b.exr": {"latent fit": {"psnr_ldr": 22.0, "peak_stops": 0.5, "abs_rel": 0.05}},
    "c.exr": {"latent fit": {"psnr_ldr": 24.0, "peak_stops": 0.2, "abs_rel": None}},
    "only-in-base.exr": {"latent fit": {"psnr_ldr": 99.0, "peak_stops": 9.0, "abs_rel": 0.9}},
})
OTHER = _report({
    "a.exr": {"latent fit": {"psnr_ldr": 21.0, "peak_stops": 0.5, "abs_rel": 0.05}},
    "b.exr": {"latent fit": {"psnr_ldr": 23.0, "peak_stops": 0.7, "abs_rel": 0.04}},
    "c.exr": {"latent fit": {"psnr_ldr": 25.0, "peak_stops": 0.1, "abs_rel": 0.03}},
})


def test_rooms_are_paired_by_name_and_differences_taken_by_hand():
    cmp = compare_reports(BASE, OTHER)
    assert cmp["n"] == 3  # the room only in BASE is left out
    psnr = cmp["metrics"]["psnr_ldr"]
    assert psnr["base"] == pytest.approx(22.0) and psnr["other"] == pytest.approx(23.0)
    assert psnr["diff"] == pytest.approx(1.0) and psnr["wins"] == 3 and psnr["n"] == 3
    # Every difference is +1, so every resampled mean is +1.
    assert psnr["ci95"] == pytest.approx([1.0, 1.0])
    peak = cmp["metrics"]["peak_stops"]  # lower is better: -0.5, +0.2, -0.1
    assert peak["diff"] == pytest.approx(-0.4 / 3) and peak["wins"] == 2 and peak["better"] == "lower"
    assert -0.5 <= peak["ci95"][0] <= peak["diff"] <= peak["ci95"][1] <= 0.2
    depth = cmp["metrics"]["abs_rel"]  # c.exr has no base value: two pairs
    assert depth["n"] == 2 and depth["diff"] == pytest.approx(-0.01) and depth["wins"] == 2
    assert "ssim_ldr" not in cmp["metrics"]
    md = comparison_markdown(cmp, "paper", "weighted")
    assert "3 rooms paired" in md and "| PSNR LDR ↑ | 22.00 [" in md and "+1.00 [+1.00, +1.00] ✓ | 3/3 |" in md


def test_rows_of_one_report_and_clear_errors():
    both = _report({"a.exr": {"encoder": {"psnr_ldr": 20.0}, "latent fit": {"psnr_ldr": 19.0}},
                    "b.exr": {"encoder": {"psnr_ldr": 21.0}, "latent fit": {"psnr_ldr": 20.0}}})
    cmp = compare_reports(both, both, "encoder", "latent fit")
    assert cmp["metrics"]["psnr_ldr"]["diff"] == pytest.approx(-1.0) and cmp["metrics"]["psnr_ldr"]["wins"] == 0
    assert "✗" in comparison_markdown(cmp)
    with pytest.raises(RoomlightError, match="no per-image values for row 'decoder'.*encoder, latent fit"):
        compare_reports(both, both, "decoder")
    with pytest.raises(RoomlightError, match="share no panorama"):
        compare_reports(both, _report({"z.exr": {"encoder": {"psnr_ldr": 1.0}}}), "encoder")


@pytest.mark.slow
def test_compare_script_prints_and_writes_the_table(tmp_path):
    (tmp_path / "a.json").write_text(json.dumps(BASE))
    (tmp_path / "b.json").write_text(json.dumps(OTHER))
    script = Path(__file__).resolve().parents[1] / "scripts" / "compare_prior_evals.py"
    out = subprocess.run([sys.executable, str(script), str(tmp_path / "a.json"), str(tmp_path / "b.json"),
                          "--labels", "paper", "weighted", "--out", str(tmp_path / "cmp.md")],
                         capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert "difference = weighted − paper" in out.stdout
    assert (tmp_path / "cmp.md").read_text() == out.stdout
    # Pooling: the room only in BASE goes to its own file; pooled, BASE is the same as before.
    rooms = BASE["per_image"]
    (tmp_path / "a1.json").write_text(json.dumps({"per_image": rooms[:3]}))
    (tmp_path / "a2.json").write_text(json.dumps({"per_image": rooms[3:]}))
    pooled = subprocess.run([sys.executable, str(script), f"{tmp_path / 'a1.json'},{tmp_path / 'a2.json'}",
                             str(tmp_path / "b.json"), "--labels", "paper", "weighted"], capture_output=True, text=True)
    assert pooled.returncode == 0 and pooled.stdout == out.stdout, pooled.stderr
    twice = subprocess.run([sys.executable, str(script), f"{tmp_path / 'a.json'},{tmp_path / 'a1.json'}",
                            str(tmp_path / "b.json")], capture_output=True, text=True)
    assert twice.returncode != 0 and "distinct rooms" in twice.stderr
    bad = subprocess.run([sys.executable, str(script), str(tmp_path / "a.json"), str(tmp_path / "missing.json")],
                         capture_output=True, text=True)
    assert bad.returncode != 0 and "cannot read the report" in bad.stderr and "Traceback" not in bad.stderr
