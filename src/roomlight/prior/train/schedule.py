"""Learning-rate schedule: linear warm-up to the peak, then cosine decay to the floor.

A pure function of the step, so the scheduler's whole state is the step counter and resuming
reproduces it exactly.
"""

from __future__ import annotations

import math

__all__ = ["learning_rate"]


def learning_rate(step: int, total_steps: int, peak: float = 2e-4, floor: float = 1e-5,
                  warmup: int = 250) -> float:
    """Learning rate of optimiser step ``step`` (0-based) in a run of ``total_steps`` steps.

    - warm-up: ``peak * (step + 1) / warmup`` for step < warmup (the first step is not wasted
      at lr 0; step warmup - 1 reaches the peak);
    - then ``floor + (peak - floor) * (1 + cos(pi t)) / 2`` with t = (step - warmup) /
      (total_steps - warmup) going from 0 to 1, so the last steps approach ``floor``.
    """
    if warmup > 0 and step < warmup:
        return peak * (step + 1) / warmup
    span = max(1, total_steps - warmup)
    t = min(max((step - warmup) / span, 0.0), 1.0)
    return floor + (peak - floor) * 0.5 * (1.0 + math.cos(math.pi * t))
