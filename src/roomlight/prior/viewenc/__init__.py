"""Training the view encoder: the photo fit's amortized start, for a given prior.

The network and its input live with the prior (:mod:`roomlight.prior.model.view_encoder`), the lifting
of a view onto the sphere with the geometry (:mod:`roomlight.core.geometry.lift`); this package trains it:

- :mod:`~roomlight.prior.viewenc.crops`: perspective training views cut from panoramas;
- :mod:`~roomlight.prior.viewenc.views`: one training view and its targets;
- :mod:`~roomlight.prior.viewenc.config`: the run's settings;
- :mod:`~roomlight.prior.viewenc.trainer`: training against the frozen prior (``roomlight train-view-encoder``).
"""

from __future__ import annotations

from roomlight.prior.viewenc.config import ViewTrainConfig
from roomlight.prior.viewenc.trainer import ViewEncoderTrainer

__all__ = ["ViewTrainConfig", "ViewEncoderTrainer"]
