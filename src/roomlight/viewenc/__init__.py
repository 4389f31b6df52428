"""The view encoder: an amortized start for fitting the prior to what a photograph shows.

- :mod:`~roomlight.viewenc.lift`: a view's pixels onto the panorama around its camera;
- :mod:`~roomlight.viewenc.crops`: perspective training views cut from panoramas;
- :mod:`~roomlight.viewenc.views`: one training view and its targets;
- :mod:`~roomlight.viewenc.network`: the network and its input;
- :mod:`~roomlight.viewenc.trainer`: training it against the frozen prior.
"""

from roomlight.viewenc.lift import PartialPanorama, lift_resolution, lift_view
from roomlight.viewenc.network import VIEW_ENCODER_DIR, ViewEncoder, view_input

__all__ = ["PartialPanorama", "lift_view", "lift_resolution", "ViewEncoder", "view_input", "VIEW_ENCODER_DIR"]
