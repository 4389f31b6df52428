"""A light: one panorama, the representation that shows it, and where it sits.

Every step that recovers, reads or scores a light passes a :class:`Light`: a fit's result, the
benchmarks' oracles, a ``fit-photo`` folder read back, the probes' rows, an exported bundle.

- ``radiance``: (H, 2H, 3) float32 linear RGB (equirectangular, row 0 at the zenith; see
  docs/conventions.md);
- ``depth``: (H, 2H) float32 radial distance from the light's centre, in the light frame's units
  (metres unless the frame scales), for a 2.5D area light; None for an env map or a sphere proxy,
  whose geometry the kind itself says;
- ``kind``: the representation (:class:`EmitterKind`): ``mesh`` (the 2.5D area light), ``envmap``
  (radiance at infinity) or ``sphere:R`` (the panorama on a sphere of radius R, scene units);
- ``frame``: (4, 4) similarity from the frame the light is used in (a camera's, or the world's) to
  the light's own frame (origin at the panorama's centre, the panorama's axes):
  p_light = s R p + t. Identity by default: the light sits at the origin of the scene it lights.

The maps are torch tensors on the CPU (the renderer's bridge and the fitters take torch); numpy
arrays are converted on the way in and :meth:`Light.to_numpy` gives them back without a copy.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
import torch

from roomlight.errors import RoomlightError, ShapeError

__all__ = ["EmitterKind", "parse_emitter_kind", "Light", "similarity_parts"]


@dataclass(frozen=True)
class EmitterKind:
    """Which representation shows the radiance: ``mesh``, ``envmap`` or ``sphere`` (with radius)."""

    name: str
    radius: float | None = None

    def __str__(self) -> str:
        return f"sphere:{self.radius:g}" if self.name == "sphere" else self.name


def parse_emitter_kind(text: str | EmitterKind) -> EmitterKind:
    """Parse ``mesh``, ``envmap`` or ``sphere:R`` (R in scene units)."""
    if isinstance(text, EmitterKind):
        return text
    name, _, arg = str(text).partition(":")
    if name in ("mesh", "envmap") and not arg:
        return EmitterKind(name)
    if name == "sphere":
        try:
            r = float(arg)
        except ValueError:
            r = float("nan")
        if r > 0:
            return EmitterKind("sphere", r)
        raise RoomlightError(f"emitter kind {text!r}: a sphere needs a positive radius, e.g. 'sphere:3.5'")
    raise RoomlightError(f"emitter kind {text!r}: expected 'mesh', 'envmap' or 'sphere:R'")


def similarity_parts(m, what: str = "light frame") -> tuple[float, np.ndarray, np.ndarray]:
    """(scale s > 0, rotation R (3, 3), translation t (3,)) of a (4, 4) similarity [s R | t]; refuses
    anything else (a shear, a reflection, a non-uniform scale, a projective last row)."""
    m = np.asarray(m, np.float64)
    if m.shape != (4, 4) or not np.isfinite(m).all() or not np.allclose(m[3], [0, 0, 0, 1]):
        raise RoomlightError(f"{what}: expected a finite 4x4 similarity with last row 0 0 0 1")
    det = float(np.linalg.det(m[:3, :3]))
    if det <= 0:
        raise RoomlightError(f"{what}: its 3x3 part is not a rotation times a positive scale (det {det:.3g})")
    s = det ** (1.0 / 3.0)
    r = m[:3, :3] / s
    if not np.allclose(r.T @ r, np.eye(3), atol=1e-4):
        raise RoomlightError(f"{what}: its 3x3 part is not a rotation times a uniform scale")
    return s, r, m[:3, 3].copy()


def _map(value, name: str) -> torch.Tensor:
    """``value`` (a tensor or an array) as a detached float32 CPU tensor, sharing memory when it can."""
    if isinstance(value, torch.Tensor):  # .to() hands back the same tensor when nothing changes
        return (value.detach() if value.requires_grad else value).to(device="cpu", dtype=torch.float32)
    try:
        a = np.asarray(value, dtype=np.float32)
    except (TypeError, ValueError):
        raise ShapeError(f"light: {name} is not a numeric array ({type(value).__name__})") from None
    if not (a.flags.c_contiguous and a.flags.writeable):  # torch wants a writable, contiguous buffer
        a = np.array(a, order="C")
    return torch.from_numpy(a)


@dataclass(frozen=True, eq=False)
class Light:
    """One light (see the module docstring for the frames and units).

    Attributes:
        radiance: (H, 2H, 3) float32 linear radiance, CPU.
        depth: (H, 2H) float32 radial depth in the light frame's units for ``mesh``; None for
            ``envmap`` and ``sphere:R``.
        kind: ``mesh``, ``envmap`` or ``sphere:R``, as given (an :class:`EmitterKind` is stored as its
            text), so that records keep the spelling they were made with.
        frame: (4, 4) float64 similarity, the user's frame (camera or world) -> the light's frame;
            read-only.

    Raises:
        ShapeError: radiance not (H, 2H, 3), or depth not the radiance's (H, 2H).
        RoomlightError: an unknown kind, a 2.5D light without depth, depth with an env map or
            sphere proxy, or a frame that is not a similarity.
    """

    radiance: torch.Tensor
    depth: torch.Tensor | None
    kind: str
    frame: np.ndarray = field(default_factory=lambda: np.eye(4))

    def __post_init__(self):
        rad = _map(self.radiance, "radiance")
        if rad.ndim != 3 or rad.shape[2] != 3 or rad.shape[0] == 0 or rad.shape[1] != 2 * rad.shape[0]:
            raise ShapeError(f"light: radiance must be (H, 2H, 3), got {tuple(rad.shape)}")
        kind = parse_emitter_kind(self.kind)
        depth = None if self.depth is None else _map(self.depth, "depth")
        if kind.name == "mesh" and depth is None:
            raise RoomlightError("light: a 2.5D area light ('mesh') needs a depth map")
        if kind.name != "mesh" and depth is not None:
            raise RoomlightError(f"light: an '{kind}' light takes no depth map (its geometry is its kind); "
                                 "pass depth=None or kind='mesh'")
        if depth is not None and tuple(depth.shape) != tuple(rad.shape[:2]):
            raise ShapeError(f"light: depth must be (H, W) = {tuple(rad.shape[:2])} like the radiance, "
                             f"got {tuple(depth.shape)}")
        frame = np.array(self.frame, dtype=np.float64)  # a copy: the caller's matrix may change later
        similarity_parts(frame, "light frame")
        frame.flags.writeable = False
        object.__setattr__(self, "radiance", rad)
        object.__setattr__(self, "depth", depth)
        object.__setattr__(self, "kind", str(self.kind))
        object.__setattr__(self, "frame", frame)

    def to_numpy(self) -> tuple[np.ndarray, np.ndarray | None]:
        """(radiance (H, 2H, 3), depth (H, 2H) or None) as float32 numpy arrays sharing the tensors' memory."""
        return self.radiance.numpy(), None if self.depth is None else self.depth.numpy()

    def with_exposure(self, ev: float) -> Light:
        """The same light 2^ev times as bright (``ev`` in stops; depth, kind and frame unchanged).

        Raises:
            RoomlightError: ``ev`` not finite or outside [-10, 10] (a factor of a thousand either way is
                more than any fit's level is off by: a larger one is a typing slip).
        """
        ev = float(ev)
        if not math.isfinite(ev) or abs(ev) > 10:
            raise RoomlightError(f"--exposure {ev}: give a number of stops between -10 and 10")
        return replace(self, radiance=self.radiance * 2.0 ** ev)

    def with_frame(self, frame) -> Light:
        """The same maps and kind with another (4, 4) frame."""
        return replace(self, frame=frame)

    def seen_from(self, m) -> Light:
        """The same light used from another frame: ``m`` (4, 4) similarity maps that frame into the
        current one, so the new frame is ``frame @ m`` (e.g. ``seen_from(world_to_camera)`` turns
        light-from-camera into light-from-world)."""
        return replace(self, frame=self.frame @ np.asarray(m, np.float64))
