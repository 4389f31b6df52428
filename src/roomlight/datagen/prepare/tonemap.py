"""The display mapping that inpainters and depth estimators see, and its exact inverse.

Learned inpainters and depth networks are trained on display-referred images, so an HDR panorama
is shown to them as

    x = k L                                   exposure: the log-average maps to middle grey 0.18
    y = reinhard_extended(x, white)           Reinhard et al. 2002 eq. 4 on luminance, white = max
    d = y ** (1 / gamma)                      gamma 2.2 per channel

and what they paint is brought back with the exact inverse of each step. The extended operator
``L_d = L (1 + L / w^2) / (1 + L)`` is inverted by the positive root of a quadratic
(:func:`roomlight.core.io.preview.inverse_reinhard_extended`); the simple operator's inverse
``L_d / (1 - L_d)`` does not invert it (it overshoots, without bound as ``L_d -> 1``), which is
why the round trip is tested to float precision.

No step clips, so :meth:`DisplayMap.inverse` undoes :meth:`DisplayMap.forward` for any
non-negative input; values above 1 (saturated colours of very bright pixels) stay above 1.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from roomlight.core.color import DISPLAY_GAMMA, MIDDLE_GREY, luminance_np
from roomlight.core.io.preview import auto_exposure_stops, inverse_reinhard_extended, reinhard_extended

__all__ = ["DisplayMap"]


@dataclass(frozen=True)
class DisplayMap:
    """Exposure, extended Reinhard and gamma, with their exact inverse.

    Attributes:
        exposure: factor k applied to the radiance first (dimensionless).
        white: the Reinhard white point, in exposed units (luminance mapped to 1).
        gamma: display gamma (encoding raises to 1 / gamma).
    """

    exposure: float
    white: float
    gamma: float = DISPLAY_GAMMA

    @classmethod
    def fit(cls, radiance: np.ndarray, mask: np.ndarray | None = None, key: float = MIDDLE_GREY) -> "DisplayMap":
        """The mapping for one panorama.

        Args:
            radiance: (H, W, 3) linear radiance, >= 0.
            mask: (H, W) bool, the pixels that count (e.g. everything outside a blind spot);
                default all.
            key: the display value of the log-average luminance (middle grey).
        """
        rad = np.asarray(radiance, np.float64)
        keep = np.ones(rad.shape[:2], bool) if mask is None else np.asarray(mask, bool)
        exposure = 2.0 ** auto_exposure_stops(rad, key=key, mask=keep)
        lum = luminance_np(rad)[keep] * exposure
        white = float(lum.max()) if lum.size and lum.max() > 0 else 1.0
        return cls(exposure=float(exposure), white=white)

    def forward(self, radiance: np.ndarray) -> np.ndarray:
        """(H, W, 3) linear radiance >= 0 -> (H, W, 3) float64 display values (luminance <= 1 up to white)."""
        y = reinhard_extended(np.asarray(radiance, np.float64) * self.exposure, self.white)
        return np.power(np.maximum(y, 0.0), 1.0 / self.gamma)

    def inverse(self, display: np.ndarray) -> np.ndarray:
        """(H, W, 3) display values >= 0 -> (H, W, 3) float64 linear radiance (negatives are clipped to 0 first)."""
        y = np.power(np.maximum(np.asarray(display, np.float64), 0.0), self.gamma)
        return inverse_reinhard_extended(y, self.white) / self.exposure

    def to_dict(self) -> dict:
        return {"exposure": self.exposure, "white": self.white, "gamma": self.gamma}
