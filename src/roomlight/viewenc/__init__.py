"""Training the view encoder: the photo fit's amortized start, for a given prior.

The network and its input live with the prior (:mod:`roomlight.model.view_encoder`), the lifting
of a view onto the sphere with the geometry (:mod:`roomlight.geometry.lift`); this package trains it:

- :mod:`~roomlight.viewenc.crops`: perspective training views cut from panoramas;
- :mod:`~roomlight.viewenc.views`: one training view and its targets;
- :mod:`~roomlight.viewenc.config`: the run's settings;
- :mod:`~roomlight.viewenc.trainer`: training against the frozen prior (``roomlight train-view-encoder``).
"""
