"""The evaluation harness every benchmark kind plugs into.

A benchmark kind (the synthetic scenes of ``roomlight bench``, the photographs of
``roomlight.evaluation.photobench``) lists its items, names its methods (:mod:`roomlight.fitting.methods`) and runs one
case; everything around that is here, written once:

- :mod:`~roomlight.evaluation.harness.runner`   the case record, listing, shards, resume, failures, Dask
- :mod:`~roomlight.evaluation.harness.records`  the results folder's files: run.json, result.json, error.json
- :mod:`~roomlight.evaluation.harness.metrics`  PSNR (LDR), RMSE (HDR), RGB angular error over masks
- :mod:`~roomlight.evaluation.harness.tables`   the tables' layout (rows, columns, bold best) as Markdown / CSV
- :mod:`~roomlight.evaluation.harness.paired`   per-item paired differences with bootstrap intervals
- :mod:`~roomlight.evaluation.harness.page`     the report page's style and Markdown tables as HTML
"""

from __future__ import annotations

from roomlight.evaluation.harness.errors import BenchError
from roomlight.evaluation.harness.metrics import METRICS, angular_error_deg, psnr_ldr, rmse_hdr, score_view
from roomlight.evaluation.harness.paired import paired_differences, paired_markdown, paired_reference
from roomlight.evaluation.harness.records import (RESULT, RUN_FILE, check_run_file, collect_failures, read_case_records,
                                        record_failure, write_json)
from roomlight.evaluation.harness.runner import Case, RunSummary, parse_shard, run_cases, shard_cases
from roomlight.evaluation.harness.tables import markdown_table, ordered, summarize

__all__ = ["BenchError", "METRICS", "angular_error_deg", "psnr_ldr", "rmse_hdr", "score_view", "paired_differences",
           "paired_markdown", "paired_reference", "RESULT", "RUN_FILE", "check_run_file", "collect_failures",
           "read_case_records", "record_failure", "write_json", "Case", "RunSummary", "parse_shard", "run_cases",
           "shard_cases", "markdown_table", "ordered", "summarize"]
