"""The photo benchmark: rendered photographs of procedural rooms, with true light transport as ground truth.

- :mod:`~roomlight.photobench.tracing`   path-traced images, z-depth and coverage through a
  :class:`~roomlight.photo.camera.PhotoCamera` (intrinsics, pose, pitch and roll)
- :mod:`~roomlight.photobench.objects`   inserted objects (principled materials) and probe spheres
- :mod:`~roomlight.photobench.roomscene` one room's Mitsuba scenes, with objects and probes added
- :mod:`~roomlight.photobench.staging`   where the camera looks and where objects and probes go
- :mod:`~roomlight.photobench.degrade`   degraded depth for the methods
- :mod:`~roomlight.photobench.case`      the photo case folder and its ``truth/``
- :mod:`~roomlight.photobench.builder`   ``roomlight bench make-photos``
- :mod:`~roomlight.photobench.scoring`   probes under a recovered light against the truth; material errors
- :mod:`~roomlight.photobench.adapter`   the one call into the photo fit (``roomlight fit-photo``)
- :mod:`~roomlight.photobench.runner`    ``roomlight bench run-photos``
- :mod:`~roomlight.photobench.report`    ``roomlight bench report-photos``

See ``docs/benchmark.md``, "The photo benchmark".
"""
