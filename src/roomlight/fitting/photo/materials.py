"""The objects' materials: one spatially uniform principled BSDF per object, fitted with the light.

Each object has an albedo (RGB base colour), a roughness and a metallic value, each the sigmoid
of a free parameter, so every value stays in (0, 1) however far Adam moves it; the parameters
start at 0, i.e. every value at 0.5 (the paper's initialisation). ``albedo_range`` can hold the
albedo inside the range real surfaces span (about 0.03 to 0.9): albedo = lo + (hi - lo) sigmoid(x),
started at 0.5 all the same. They reach Mitsuba's
``principled`` BSDF of the object's mesh (``<id>.bsdf.base_color.value``, ``.roughness.value``,
``.metallic.value``) through :meth:`ObjectMaterials.scene_values` with every render, so the
renderer's gradients reach them.
"""

from __future__ import annotations

import math

import torch

from roomlight.errors import RoomlightError
from roomlight.core.render.materials import principled_bsdf  # noqa: F401  (part of this module's API)

__all__ = ["ObjectMaterials", "object_id", "principled_bsdf", "PARTS"]

#: What a material has: fitted by default, any of them can be held at known values.
PARTS = ("albedo", "roughness", "metallic")


def object_id(label: int, kind: str = "object") -> str:
    """The Mitsuba shape id of the object with mask label ``label`` (``kind`` ``receiver``: of its shadow
    receiver, :mod:`roomlight.fitting.photo.receivers`)."""
    return f"{kind}_{int(label)}"


class ObjectMaterials(torch.nn.Module):
    """Sigmoid-parametrised principled materials of the objects ``labels``.

    Attributes:
        labels: the objects' mask labels, in order.
        logits: (n, 5) parameters: albedo R, G, B, roughness, metallic (before the sigmoid).
        free: the parts that are fitted (:data:`PARTS`); the others keep the values they are given.
        kind: whose materials: the objects' (``object``) or their shadow receivers' (``receiver``); it
            names the Mitsuba shapes (:func:`object_id`).
    """

    def __init__(self, labels: list[int], init: float = 0.5, free=PARTS, albedo_range=(0.0, 1.0),
                 kind: str = "object"):
        super().__init__()
        self.labels = [int(lab) for lab in labels]
        self.kind = str(kind)
        lo, hi = (float(a) for a in albedo_range)
        if not 0.0 <= lo < init < hi <= 1.0:
            raise RoomlightError(f"materials: albedo_range must hold the start {init} inside [0, 1], got {albedo_range}")
        self.albedo_range = (lo, hi)
        start = torch.logit(torch.tensor(float(init)))
        self.logits = torch.nn.Parameter(torch.full((len(self.labels), 5), float(start)))
        if self.bounded:
            with torch.no_grad():
                self.logits[:, :3] = torch.logit(torch.tensor((float(init) - lo) / (hi - lo)))
        unknown = set(free) - set(PARTS)
        if unknown:
            raise RoomlightError(f"materials: unknown part(s) {sorted(unknown)}; choose from {', '.join(PARTS)}")
        self.free = tuple(p for p in PARTS if p in free)
        columns = {"albedo": [0, 1, 2], "roughness": [3], "metallic": [4]}
        mask = torch.zeros(5)
        for part in self.free:
            mask[columns[part]] = 1.0
        self.register_buffer("free_mask", mask, persistent=False)
        if len(self.free) < len(PARTS):
            # Held parts get no gradient, so Adam leaves them exactly where set_values put them.
            self.logits.register_hook(lambda g: g * self.free_mask)

    @property
    def bounded(self) -> bool:
        """Whether the albedo is held inside a range narrower than (0, 1)."""
        return self.albedo_range != (0.0, 1.0)

    def values(self) -> torch.Tensor:
        """(n, 5) albedo R, G, B, roughness, metallic in (0, 1) (the albedo inside ``albedo_range``),
        differentiable."""
        v = torch.sigmoid(self.logits)
        if not self.bounded:
            return v
        lo, hi = self.albedo_range
        return torch.cat([lo + (hi - lo) * v[:, :3], v[:, 3:]], dim=1)

    def albedo_prior(self, typical: float, average: str = "arithmetic") -> torch.Tensor:
        """Mean over the objects of (1 - metallic) * ln(a / typical)^2, a the object's mean albedo.

        A photograph alone cannot split an object's brightness between its albedo and the light: the
        same pixels come from twice the light on half the albedo. This term is the log-normal prior
        on reflectance that settles it, centred on ``typical``. Metals (whose base colour is a
        specular reflectance, often near 1) are exempt by their fitted metallic value, taken as a
        constant so that the term cannot be escaped by making an object metallic.

        ``average`` says which mean over R, G, B is held:

        * ``"arithmetic"`` (default): a = mean over the channels of the albedo. Its gradient is the
          same in absolute terms on every channel, so pulling a bright object down darkens its weak
          channels proportionally more and tints it.
        * ``"geometric"``: ln a = mean over the channels of ln(albedo). Its gradient is the same on
          every channel's log albedo, so it scales an object without tinting it, and a per-channel
          light gain whose log sums to zero (the white balance) leaves it unchanged. Colour-blind by
          construction, yet on rendered photos it fitted worse than the arithmetic mean, colour
          included (docs/photo.md); in the cases looked at, a saturated object's darkest channel
          dragged its geometric mean down and the fit brightened the other channels to answer.

        A scalar tensor, 0 without objects.
        """
        if not self.labels:
            return self.logits.sum() * 0.0
        v = self.values()
        dielectric = 1.0 - v[:, 4].detach()
        if average == "geometric" and self.bounded:
            log_ratio = torch.log(v[:, :3]).mean(dim=1) - math.log(float(typical))
        elif average == "geometric":
            # ln of the sigmoid, computed stably: ln sigmoid(x) = -softplus(-x).
            log_ratio = -torch.nn.functional.softplus(-self.logits[:, :3]).mean(dim=1) - math.log(float(typical))
        elif average == "arithmetic":
            # written as first measured, so that its runs reproduce to the last digit
            log_ratio = torch.log(v[:, :3].mean(dim=1).clamp_min(1e-6) / float(typical))
        else:
            raise RoomlightError(f"albedo prior: unknown average {average!r}; choose geometric or arithmetic")
        return (dielectric * log_ratio.square()).mean()

    def metal_band_term(self, band=(0.06, 0.45)) -> torch.Tensor:
        """Mean over the objects of metallic * d^2, d the log-distance of the object's mean albedo a from
        the nearer edge of ``band`` when a lies inside it (0 outside).

        A metal's base colour is its reflectance at normal incidence, and every pure metal reflects at
        least about half the light (titanium, chromium, iron 0.50-0.56 averaged over R, G, B; silver,
        aluminium 0.9); a specular-only surface reflecting a few per cent is a dielectric's clear coat
        (F0 0.02-0.05). A fitted "metal" in between exists only because the fit traded its albedo against
        the light (a black glossy object read as a grey metal under a light several times too dim). The
        term pushes such an object out of the band by the shorter way, or towards a dielectric: its
        gradient reaches the albedo and the metallic value alike. A scalar tensor, 0 without objects.
        """
        if not self.labels:
            return self.logits.sum() * 0.0
        v = self.values()
        lo, hi = (math.log(float(b)) for b in band)
        log_a = torch.log(v[:, :3].mean(dim=1).clamp_min(1e-6))
        inside = torch.minimum(log_a - lo, hi - log_a).clamp_min(0)
        return (v[:, 4] * inside.square()).mean()

    def scene_values(self) -> dict[str, torch.Tensor]:
        """Each object's BSDF parameters by their ``mi.traverse`` key."""
        v = self.values()
        out: dict[str, torch.Tensor] = {}
        for k, label in enumerate(self.labels):
            oid = object_id(label, self.kind)
            out[f"{oid}.bsdf.base_color.value"] = v[k, :3]
            out[f"{oid}.bsdf.roughness.value"] = v[k, 3:4]
            out[f"{oid}.bsdf.metallic.value"] = v[k, 4:5]
        return out

    def bsdf(self, label: int) -> dict:
        """The current material of object ``label`` as a Mitsuba BSDF dict."""
        v = self.values().detach()[self.labels.index(int(label))].tolist()
        return principled_bsdf(v[:3], v[3], v[4])

    def set_values(self, label: int, albedo=None, roughness: float | None = None, metallic: float | None = None) -> None:
        """Set (some of) an object's values, e.g. to start from or hold known materials; in (0, 1), the
        albedo inside ``albedo_range`` (a value outside is held at its bound)."""
        k = self.labels.index(int(label))
        eps = 1e-6
        with torch.no_grad():
            if albedo is not None:
                lo, hi = self.albedo_range
                a = (torch.as_tensor(albedo, dtype=torch.float32) - lo) / (hi - lo)
                self.logits[k, :3] = torch.logit(a.clamp(eps, 1 - eps))
            if roughness is not None:
                self.logits[k, 3] = torch.logit(torch.tensor(float(roughness)).clamp(eps, 1 - eps))
            if metallic is not None:
                self.logits[k, 4] = torch.logit(torch.tensor(float(metallic)).clamp(eps, 1 - eps))

    def to_json(self) -> list[dict]:
        """One entry per object: label, Mitsuba id, albedo, roughness, metallic."""
        v = self.values().detach().tolist()
        return [{"label": label, "id": object_id(label, self.kind), "albedo": [round(x, 6) for x in v[k][:3]],
                 "roughness": round(v[k][3], 6), "metallic": round(v[k][4], 6)}
                for k, label in enumerate(self.labels)]
