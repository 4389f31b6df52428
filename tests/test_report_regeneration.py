"""The reports committed beside the benchmark results are what today's code writes from those results.

A refactor of the harness must not change a report whose numbers did not change: each committed
results folder is copied, its report rebuilt from the case records alone (``bench report`` /
``bench report-photos --no-figures``) and compared byte for byte with the committed ``report.md``.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from click.testing import CliRunner

from roomlight.cli.main import cli

RESULTS = Path(__file__).parents[1] / "benchmarks" / "results"


@pytest.mark.parametrize("folder, command", [("unseen64", "report"), ("photos24", "report-photos"),
                                             ("photos24-reflectance-prior", "report-photos"),
                                             ("wide24-reflectance-prior", "report-photos"),
                                             ("wide24-room-bound", "report-photos"),
                                             ("photos24-room-bound", "report-photos"),
                                             ("wide24-estimate", "report-photos")])
def test_a_committed_report_is_rebuilt_byte_for_byte(folder, command, tmp_path):
    src = RESULTS / folder
    work = tmp_path / folder
    shutil.copytree(src, work)
    r = CliRunner().invoke(cli, ["bench", command, str(work), "--no-figures"], catch_exceptions=False)
    assert r.exit_code == 0, r.output
    rebuilt = (work / "report" / "report.md").read_bytes()
    assert rebuilt == (src / "report.md").read_bytes(), f"{folder}: the rebuilt report differs from the committed one"


@pytest.mark.parametrize("folder", ["crops-rooms", "crops-blender", "crops-rooms-estimate-do"])
def test_a_committed_crop_report_is_rebuilt_byte_for_byte(folder, tmp_path):
    work = tmp_path / folder
    shutil.copytree(RESULTS / folder, work)
    (work / "report.md").unlink()
    r = CliRunner().invoke(cli, ["bench", "report-crops", str(work)], catch_exceptions=False)
    assert r.exit_code == 0, r.output
    assert (work / "report.md").read_bytes() == (RESULTS / folder / "report.md").read_bytes()
