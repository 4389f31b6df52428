"""The rows of the ablation table: what each removes from the full prior (loss weights, model switches)."""

from __future__ import annotations

__all__ = ["ROWS", "ROW_LABELS"]

#: Row name -> (loss weight overrides, model overrides).
ROWS: dict[str, tuple[dict, dict]] = {
    "full": ({}, {}),
    "no-peak": ({"peak": 0.0}, {}),
    "no-gradient": ({"grad_radiance": 0.0, "grad_depth": 0.0}, {}),
    "no-adagn": ({}, {"adagn": False}),
    "no-latitude": ({}, {"latitude": False}),
    "none": ({"peak": 0.0, "grad_radiance": 0.0, "grad_depth": 0.0}, {"adagn": False, "latitude": False}),
}
ROW_LABELS = {"full": "Full model", "no-peak": "w/o L_peak", "no-gradient": "w/o L_∇^L, L_∇^D",
              "no-adagn": "w/o AdaGN", "no-latitude": "w/o (cos θ, sin θ) channels",
              "none": "w/o L_peak, L_∇^L, L_∇^D, AdaGN, (cos θ, sin θ)"}
