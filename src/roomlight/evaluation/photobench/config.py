"""Settings of ``roomlight bench make-photos`` (the photo benchmark's build)."""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass

from roomlight.core.color import MIDDLE_GREY
from roomlight.core.config import StrictConfig
from roomlight.errors import RoomlightError

__all__ = ["PhotoBenchConfig", "DEPTH_FIELDS"]

#: Settings that change only the depth file the methods get (``depth.exr``): a photo built with
#: other values of these alone is updated in place instead of being rendered again.
DEPTH_FIELDS = ("depth_noise", "depth_scale")


@dataclass(frozen=True)
class PhotoBenchConfig(StrictConfig):
    """Settings of the photo benchmark; the defaults suit a CPU.

    Lengths in metres, angles in degrees, sizes in pixels.
    """

    n: int = 25                                          #: photos (indices 0 .. n-1)
    seed: int = 0                                        #: base seed (each photo seeds from it and its index)
    width: int = 256                                     #: image width
    height: int = 192                                    #: image height
    fov: float = 60.0                                    #: horizontal field of view
    spp: int = 256                                       #: samples per pixel of the photo
    probe_spp: int = 1024                                #: samples per pixel of the probe renders (around the probes)
    max_depth: int = 5                                   #: longest light path of the ground-truth renders
    eye_height: tuple[float, float] = (1.5, 1.7)         #: camera height range above the floor
    objects: tuple[int, int] = (2, 3)                    #: inserted objects per photo (inclusive range)
    probes: int = 3                                      #: probe positions per photo
    inserts: int = 2                                     #: new objects at the first probe positions, with their truth
    object_size: tuple[float, float] = (0.05, 0.08)      #: object bounding radius / its distance to the camera
    probe_size: float = 0.045                            #: probe radius / its distance to the camera
    metal_fraction: float = 0.3                          #: chance that an object is a metal (metallic 1)
    roughness: tuple[float, float] = (0.15, 0.8)         #: object roughness range
    min_pixels: int = 24                                 #: whole pixels each object and probe must show
    key: float = MIDDLE_GREY                             #: exposure key: the frame's log-average luminance
    oracle_height: int = 64                              #: oracle panorama height H (width 2H)
    oracle_spp: int = 256                                #: samples per pixel of the oracle panorama
    supersample: int = 4                                 #: mask rays per pixel along each axis
    depth_noise: float = 0.0                             #: relative smooth noise on the methods' depth (0: exact)
    depth_scale: float = 1.0                             #: scale of the methods' depth (1: exact)

    def __post_init__(self):
        checks = [(self.n >= 1, "--n must be at least 1"),
                  (self.width >= 8 and self.height >= 8, "--res: the image must be at least 8x8 pixels"),
                  (0.0 < self.fov < 150.0, "--fov must be in (0, 150) degrees"),
                  (self.spp >= 1 and self.oracle_spp >= 1, "--spp must be at least 1"),
                  (self.probe_spp >= 2, "--probe-spp must be at least 2 (two independent halves)"),
                  (self.max_depth >= 2, "max_depth must be at least 2"),
                  (0.0 < self.eye_height[0] <= self.eye_height[1], "eye_height must be an increasing positive range"),
                  # a mask with a single non-zero value reads as a binary mask, whose connected
                  # components would be renumbered: two objects keep the labels as written
                  (2 <= self.objects[0] <= self.objects[1], "objects must be an increasing range from 2"),
                  (self.probes >= 1, "probes must be at least 1"),
                  (0 <= self.inserts <= self.probes, "inserts must be between 0 and the number of probes"),
                  (0.0 < self.object_size[0] <= self.object_size[1] < 0.5, "object_size must be in (0, 0.5)"),
                  (0.0 < self.probe_size < 0.5, "probe_size must be in (0, 0.5)"),
                  (0.0 <= self.metal_fraction <= 1.0, "metal_fraction must be in [0, 1]"),
                  (0.0 <= self.roughness[0] <= self.roughness[1] <= 1.0, "roughness must be a range in [0, 1]"),
                  (self.key > 0.0, "--key must be positive"),
                  (self.oracle_height >= 4, "oracle_height must be at least 4"),
                  (self.supersample >= 1, "supersample must be at least 1"),
                  (0.0 <= self.depth_noise < 1.0, "--depth-noise must be in [0, 1)"),
                  (self.depth_scale > 0.0, "--depth-scale must be positive")]
        for ok, message in checks:
            if not ok:
                raise RoomlightError(f"make-photos: {message}")

    def to_dict(self) -> dict:
        return json.loads(json.dumps(asdict(self)))

    def scene_settings(self) -> dict:
        """The settings a photo's renders depend on (all but ``n`` and the depth degradation): a
        built photo is reused only when they match."""
        d = self.to_dict()
        for k in ("n", *DEPTH_FIELDS):
            d.pop(k)
        return d

    def depth_settings(self) -> dict:
        return {k: getattr(self, k) for k in DEPTH_FIELDS}

    def override(self, **changes) -> PhotoBenchConfig:
        """A copy with the fields that are not None changed; unknown names and wrong types are refused."""
        return super().override(**{k: v for k, v in changes.items() if v is not None})
