"""The photo benchmark: rendered photographs of procedural rooms, with true light transport as ground truth.

- :mod:`~roomlight.evaluation.photobench.tracing`   path-traced images, z-depth and coverage through a
  :class:`~roomlight.fitting.photo.camera.PhotoCamera` (intrinsics, pose, pitch and roll)
- :mod:`~roomlight.evaluation.photobench.objects`   inserted objects (principled materials) and probe spheres
- :mod:`~roomlight.evaluation.photobench.roomscene` one room's Mitsuba scenes, with objects and probes added
- :mod:`~roomlight.evaluation.photobench.staging`   where the camera looks and where objects and probes go
- :mod:`~roomlight.evaluation.photobench.degrade`   degraded depth for the methods
- :mod:`~roomlight.evaluation.photobench.case`      the photo case folder and its ``truth/``
- :mod:`~roomlight.evaluation.photobench.builder`   ``roomlight bench make-photos``
- :mod:`~roomlight.evaluation.photobench.scoring`   probes under a recovered light against the truth; material errors
- :mod:`~roomlight.evaluation.photobench.adapter`   the one call into the photo fit (``roomlight fit-photo``)
- :mod:`~roomlight.evaluation.photobench.runner`    ``roomlight bench run-photos``
- :mod:`~roomlight.evaluation.photobench.report`    ``roomlight bench report-photos``

See ``docs/benchmark.md``, "The photo benchmark".
"""

from __future__ import annotations

from roomlight.evaluation.photobench.builder import make_photo_benchmark, read_photo_manifest
from roomlight.evaluation.photobench.config import PhotoBenchConfig
from roomlight.evaluation.photobench.report import write_photo_report
from roomlight.evaluation.photobench.runner import run_photo_benchmark

__all__ = ["make_photo_benchmark", "read_photo_manifest", "PhotoBenchConfig", "write_photo_report", "run_photo_benchmark"]
