"""The paper's analyses, one command each (``roomlight experiment ...``; docs/experiments.md).

- :mod:`~roomlight.evaluation.experiments.capacity`   how well one 2.5D area light stands in for a 3-D room
- :mod:`~roomlight.evaluation.experiments.ablation`   the ablation table: six priors trained on one budget
- :mod:`~roomlight.evaluation.experiments.cost`       the cost table on this machine
"""

from __future__ import annotations

from roomlight.evaluation.experiments.ablation import AblationConfig, run_ablation
from roomlight.evaluation.experiments.capacity import CapacityConfig, run_capacity
from roomlight.evaluation.experiments.cost import CostConfig, run_cost

__all__ = ["AblationConfig", "run_ablation", "CapacityConfig", "run_capacity", "CostConfig", "run_cost"]
