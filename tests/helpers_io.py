"""Shared helpers of the roomlight.core.io tests (fixtures are re-exported by the test modules)."""

from __future__ import annotations

import numpy as np




def make_radiance(rng, h=8, w=16):
    """Positive HDR radiance spanning several decades, (H, W, 3) float32."""
    base = rng.random((h, w, 3)) + 0.05
    return (base * np.exp(rng.normal(0.0, 2.0, (h, w, 1)))).astype(np.float32)


def make_depth(rng, h=8, w=16):
    return (0.5 + 9.5 * rng.random((h, w))).astype(np.float32)


def message(excinfo) -> str:
    return str(excinfo.value)


