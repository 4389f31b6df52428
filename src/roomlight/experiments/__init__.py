"""The paper's analyses, one command each (``roomlight experiment ...``; docs/experiments.md).

- :mod:`~roomlight.experiments.capacity`   how well one 2.5D area light stands in for a 3-D room
- :mod:`~roomlight.experiments.ablation`   the ablation table: six priors trained on one budget
- :mod:`~roomlight.experiments.cost`       the cost table on this machine
"""
