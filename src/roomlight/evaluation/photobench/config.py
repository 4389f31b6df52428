"""Settings of ``roomlight bench make-photos`` (the photo benchmark's build)."""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass

from roomlight.core.color import MIDDLE_GREY
from roomlight.core.config import StrictConfig
from roomlight.errors import RoomlightError
from roomlight.evaluation.photobench.objects import METAL_COLOURS

__all__ = ["PhotoBenchConfig", "DEPTH_FIELDS", "INSERT_FIELDS", "SUITES", "INSERT_PLACEMENTS", "INSERT_STRATA", "suite_config"]

#: Settings that change only the depth file the methods get (``depth.exr``): a photo built with
#: other values of these alone is updated in place instead of being rendered again.
DEPTH_FIELDS = ("depth_noise", "depth_scale")
#: Settings that change only the inserted objects' clean truth (``truth/insert_clean.exr``): a photo built
#: with other values of these alone gets that render made again in place. A photo recorded without them was
#: built before the clean truth existed: its value is 0 (none).
INSERT_FIELDS = ("insert_spp",)
#: The photo suites: the generator's own rooms and cameras, and the wide suite (photobench.variety).
SUITES = ("rooms", "wide")
_WIDE_DEFAULTS = {"suite": "rooms", "fov_range": None, "pitch_range": None, "captured_every": 0,
                  "insert_placement": "probes", "metal_colours": "as-drawn"}
#: Where the inserted objects go: at the probes (where the reference light is captured) or spread over the
#: visible surfaces by distance (near, middle, far) and height (raised: a table top, a shelf).
INSERT_PLACEMENTS = ("probes", "stratified")
#: The strata of ``stratified`` placement, in the order objects are drawn for them.
INSERT_STRATA = ("near", "middle", "far", "raised")


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
    insert_spp: int = 4096                               #: samples per pixel of the inserted objects' clean truth (0: none)
    max_depth: int = 5                                   #: longest light path of the ground-truth renders
    eye_height: tuple[float, float] = (1.5, 1.7)         #: camera height range above the floor
    objects: tuple[int, int] = (2, 3)                    #: inserted objects per photo (inclusive range)
    probes: int = 3                                      #: probe positions per photo
    inserts: int = 2                                     #: new objects at the first probe positions, with their truth
    object_size: tuple[float, float] = (0.05, 0.08)      #: object bounding radius / its distance to the camera
    probe_size: float = 0.045                            #: probe radius / its distance to the camera
    metal_fraction: float = 0.3                          #: chance that an object is a metal (metallic 1)
    metal_colours: str = "as-drawn"                      #: a metal's base colour: as drawn (any albedo) or a real metal's
    roughness: tuple[float, float] = (0.15, 0.8)         #: object roughness range
    min_pixels: int = 24                                 #: whole pixels each object and probe must show
    key: float = MIDDLE_GREY                             #: exposure key: the frame's log-average luminance
    oracle_height: int = 64                              #: oracle panorama height H (width 2H)
    oracle_spp: int = 256                                #: samples per pixel of the oracle panorama
    supersample: int = 4                                 #: mask rays per pixel along each axis
    depth_noise: float = 0.0                             #: relative smooth noise on the methods' depth (0: exact)
    depth_scale: float = 1.0                             #: scale of the methods' depth (1: exact)
    # The wide suite (photobench.variety); at these defaults a photo is built exactly as the original suite's.
    suite: str = "rooms"                                 #: ``rooms`` (the generator's own) or ``wide``
    fov_range: tuple[float, float] | None = None         #: a horizontal field of view drawn per photo (wide)
    pitch_range: tuple[float, float] | None = None       #: a camera pitch drawn per staging attempt (wide)
    captured_every: int = 0                              #: every k-th photo lit by a captured panorama (0: none)
    insert_placement: str = "probes"                     #: where inserted objects go: probes or stratified

    def __post_init__(self):
        checks = [(self.n >= 1, "--n must be at least 1"),
                  (self.width >= 8 and self.height >= 8, "--res: the image must be at least 8x8 pixels"),
                  (0.0 < self.fov < 150.0, "--fov must be in (0, 150) degrees"),
                  (self.spp >= 1 and self.oracle_spp >= 1, "--spp must be at least 1"),
                  (self.probe_spp >= 2, "--probe-spp must be at least 2 (two independent halves)"),
                  (self.insert_spp >= 0, "--insert-spp must be at least 0 (0: no clean truth)"),
                  (self.max_depth >= 2, "max_depth must be at least 2"),
                  (0.0 < self.eye_height[0] <= self.eye_height[1], "eye_height must be an increasing positive range"),
                  # a mask with a single non-zero value reads as a binary mask, whose connected
                  # components would be renumbered: two objects keep the labels as written
                  (2 <= self.objects[0] <= self.objects[1], "objects must be an increasing range from 2"),
                  (self.probes >= 1, "probes must be at least 1"),
                  (self.insert_placement in INSERT_PLACEMENTS,
                   f"insert_placement must be one of {', '.join(INSERT_PLACEMENTS)}"),
                  (0 <= self.inserts <= (self.probes if self.insert_placement == "probes" else len(INSERT_STRATA)),
                   "inserts must be between 0 and the number of probes (stratified: 0 to 4, one per stratum)"),
                  (0.0 < self.object_size[0] <= self.object_size[1] < 0.5, "object_size must be in (0, 0.5)"),
                  (0.0 < self.probe_size < 0.5, "probe_size must be in (0, 0.5)"),
                  (0.0 <= self.metal_fraction <= 1.0, "metal_fraction must be in [0, 1]"),
                  (self.metal_colours in METAL_COLOURS, f"metal_colours must be one of {', '.join(METAL_COLOURS)}"),
                  (0.0 <= self.roughness[0] <= self.roughness[1] <= 1.0, "roughness must be a range in [0, 1]"),
                  (self.key > 0.0, "--key must be positive"),
                  (self.oracle_height >= 4, "oracle_height must be at least 4"),
                  (self.supersample >= 1, "supersample must be at least 1"),
                  (0.0 <= self.depth_noise < 1.0, "--depth-noise must be in [0, 1)"),
                  (self.depth_scale > 0.0, "--depth-scale must be positive"),
                  (self.suite in SUITES, f"--suite must be one of {', '.join(SUITES)}"),
                  (self.fov_range is None or 0.0 < self.fov_range[0] <= self.fov_range[1] < 150.0,
                   "fov_range must be an increasing range in (0, 150) degrees"),
                  (self.pitch_range is None or -89.0 < self.pitch_range[0] <= self.pitch_range[1] < 89.0,
                   "pitch_range must be an increasing range in (-89, 89) degrees"),
                  (self.captured_every >= 0, "captured_every must be at least 0")]
        for ok, message in checks:
            if not ok:
                raise RoomlightError(f"make-photos: {message}")

    def to_dict(self) -> dict:
        return json.loads(json.dumps(asdict(self)))

    def scene_settings(self) -> dict:
        """The settings a photo's renders depend on (all but ``n``, the depth degradation and the clean
        insertion truth's samples): a built photo is reused only when they match. The wide suite's fields
        are left out at their defaults, so photos built before they existed still match."""
        d = self.to_dict()
        for k in ("n", *DEPTH_FIELDS, *INSERT_FIELDS):
            d.pop(k)
        for k, default in _WIDE_DEFAULTS.items():
            if d[k] == default:
                d.pop(k)
        return d

    def depth_settings(self) -> dict:
        return {k: getattr(self, k) for k in DEPTH_FIELDS}

    def insert_settings(self) -> dict:
        """The clean insertion truth's settings, as a photo's record keeps them (``insert_truth``)."""
        return {k: getattr(self, k) for k in INSERT_FIELDS}

    def override(self, **changes) -> PhotoBenchConfig:
        """A copy with the fields that are not None changed; unknown names and wrong types are refused."""
        return super().override(**{k: v for k, v in changes.items() if v is not None})


def suite_config(suite: str, **fields) -> PhotoBenchConfig:
    """The settings of a suite, ``fields`` replacing its own: ``rooms`` is :class:`PhotoBenchConfig`'s
    defaults; ``wide`` draws its rooms, cameras, objects and light as :mod:`~roomlight.evaluation.photobench.variety`
    says (fixed here, before any photo of it is fitted)."""
    if suite not in SUITES:
        raise RoomlightError(f"make-photos: --suite must be one of {', '.join(SUITES)}, got {suite!r}")
    base = {} if suite == "rooms" else dict(
        suite="wide", eye_height=(0.75, 1.75), fov_range=(40.0, 90.0), pitch_range=(-35.0, 10.0), captured_every=3,
        roughness=(0.05, 0.8), metal_fraction=0.3)
    return PhotoBenchConfig(**{**base, **fields})
