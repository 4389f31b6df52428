"""Run logging: a JSONL file always, TensorBoard when it is installed.

``RUN/log.jsonl`` gets one JSON object per event (``train``, ``val``, ``skipped``, ``checkpoint``,
``stop``), so a run can be plotted or audited without extra packages. When ``tensorboard`` is
importable the same scalars, and the image panels, go to ``RUN/tensorboard``; otherwise a note
says how to get it.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np

from roomlight.prior.train.checkpoint import atomic_write_text

__all__ = ["RunLogger"]


class RunLogger:
    """Writes the JSONL log and (optionally) TensorBoard events of a run; no-op when disabled.

    Args:
        run_dir: the run folder.
        enabled: False on DDP ranks other than 0.
        resume_step: when resuming, log entries after this step (written by the interrupted
            process after its last checkpoint) are dropped so the log reads like one run.
        note: function receiving one-line human messages.
    """

    def __init__(self, run_dir: str | Path, enabled: bool = True, resume_step: int | None = None, note=print):
        self.enabled = enabled
        self.path = Path(run_dir) / "log.jsonl"
        self.tb = None
        if not enabled:
            return
        if resume_step is not None and self.path.exists():
            keep = []
            for line in self.path.read_text().splitlines():
                try:
                    if json.loads(line).get("step", 0) <= resume_step:
                        keep.append(line)
                except json.JSONDecodeError:
                    continue  # a line cut by a kill
            atomic_write_text(self.path, "".join(k + "\n" for k in keep))
        self._file = open(self.path, "a")
        try:
            from torch.utils.tensorboard import SummaryWriter

            self.tb = SummaryWriter(str(Path(run_dir) / "tensorboard"))
        except ImportError:
            note("note: tensorboard is not installed, so scalars go to log.jsonl only and image panels "
                 "to RUN/images/ (pip install tensorboard to get TensorBoard logs)")

    def event(self, kind: str, step: int, **values) -> None:
        """Append one JSON line ``{"event": kind, "step": step, "time": ..., **values}``."""
        if not self.enabled:
            return
        rec = {"event": kind, "step": int(step), "time": round(time.time(), 3), **values}
        self._file.write(json.dumps(rec) + "\n")
        self._file.flush()

    def scalars(self, prefix: str, step: int, values: dict) -> None:
        """Scalars to TensorBoard as ``prefix/name``."""
        if self.tb is not None:
            for k, v in values.items():
                if isinstance(v, (int, float)):
                    self.tb.add_scalar(f"{prefix}/{k}", v, step)

    def image(self, tag: str, step: int, image: np.ndarray) -> None:
        """An (H, W, 3) uint8 image to TensorBoard."""
        if self.tb is not None:
            self.tb.add_image(tag, image, step, dataformats="HWC")

    def close(self) -> None:
        if not self.enabled:
            return
        self._file.close()
        if self.tb is not None:
            self.tb.close()
