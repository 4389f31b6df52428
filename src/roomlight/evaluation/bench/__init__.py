"""The synthetic benchmark of the paper (§4.2, supplementary "Synthetic scene design").

- :mod:`~roomlight.evaluation.bench.placement`  the protocol for one panorama: camera, boxes, strata, objects
- :mod:`~roomlight.evaluation.bench.recording`  the camera: exposure rule and 8-bit recording
- :mod:`~roomlight.evaluation.bench.rendering`  renders at high spp (in passes) and object masks
- :mod:`~roomlight.evaluation.bench.builder`    ``roomlight bench make``: scene folders + manifest
- :mod:`~roomlight.evaluation.harness.metrics`    PSNR (LDR), RMSE (HDR), RGB angular error over masks
- :mod:`~roomlight.evaluation.bench.runner`     ``roomlight bench run``: fit, re-render, score (resumable, sharded)
- :mod:`~roomlight.evaluation.bench.report`     ``roomlight bench report``: Table 2 as Markdown / CSV / JSON
- :mod:`~roomlight.evaluation.bench.figures`    per-scene figures and index.html

See ``docs/benchmark.md``.
"""

from __future__ import annotations

from roomlight.evaluation.bench.builder import (
           BENCH_MATERIALS,
           BenchConfig,
           make_benchmark,
           read_manifest,
)
from roomlight.evaluation.harness.errors import BenchError
from roomlight.evaluation.harness.metrics import (
           METRICS,
           angular_error_deg,
           psnr_ldr,
           rmse_hdr,
           score_view,
)
from roomlight.evaluation.bench.placement import PlacementConfig, PlacementError, place_objects
from roomlight.evaluation.bench.recording import exposure_for, record_ldr
from roomlight.evaluation.bench.report import write_report
from roomlight.evaluation.bench.runner import ORACLE, parse_shard, run_benchmark

__all__ = ["BENCH_MATERIALS", "BenchConfig", "make_benchmark", "read_manifest", "BenchError", "METRICS",
           "angular_error_deg", "psnr_ldr", "rmse_hdr", "score_view", "PlacementConfig", "PlacementError",
           "place_objects", "exposure_for", "record_ldr", "write_report", "ORACLE", "parse_shard", "run_benchmark"]
