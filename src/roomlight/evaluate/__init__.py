"""The evaluation harness every benchmark kind plugs into.

A benchmark kind (the synthetic scenes of ``roomlight bench``, the photographs of
``roomlight.photobench``) lists its items, names its methods (:mod:`roomlight.methods`) and runs one
case; everything around that is here, written once:

- :mod:`~roomlight.evaluate.runner`   the case record, listing, shards, resume, failures, Dask
- :mod:`~roomlight.evaluate.records`  the results folder's files: run.json, result.json, error.json
- :mod:`~roomlight.evaluate.metrics`  PSNR (LDR), RMSE (HDR), RGB angular error over masks
- :mod:`~roomlight.evaluate.tables`   the tables' layout (rows, columns, bold best) as Markdown / CSV
- :mod:`~roomlight.evaluate.paired`   per-item paired differences with bootstrap intervals
- :mod:`~roomlight.evaluate.page`     the report page's style and Markdown tables as HTML
"""

from __future__ import annotations

from roomlight.evaluate.errors import BenchError
from roomlight.evaluate.metrics import METRICS, angular_error_deg, psnr_ldr, rmse_hdr, score_view
from roomlight.evaluate.paired import paired_differences, paired_markdown, paired_reference
from roomlight.evaluate.records import (RESULT, RUN_FILE, check_run_file, collect_failures, read_case_records,
                                        record_failure, write_json)
from roomlight.evaluate.runner import Case, RunSummary, parse_shard, run_cases, shard_cases
from roomlight.evaluate.tables import markdown_table, ordered, summarize

__all__ = ["BenchError", "METRICS", "angular_error_deg", "psnr_ldr", "rmse_hdr", "score_view", "paired_differences",
           "paired_markdown", "paired_reference", "RESULT", "RUN_FILE", "check_run_file", "collect_failures",
           "read_case_records", "record_failure", "write_json", "Case", "RunSummary", "parse_shard", "run_cases",
           "shard_cases", "markdown_table", "ordered", "summarize"]
