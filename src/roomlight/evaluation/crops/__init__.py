"""The field's three-sphere protocol (StyleLight, DiffusionLight, LuxDiT): a perspective crop of a
panorama in, a panorama out, three spheres rendered under both and compared.

- :mod:`~roomlight.evaluation.crops.metrics`  tone mapping and the four sphere scores, as the field computes them
"""

from __future__ import annotations

from roomlight.evaluation.crops.metrics import (CROP_TONEMAP, SCORE_TONEMAP, Tonemap, sphere_scores, tonemap)

__all__ = ["CROP_TONEMAP", "SCORE_TONEMAP", "Tonemap", "sphere_scores", "tonemap"]
