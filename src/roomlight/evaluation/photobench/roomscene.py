"""One procedural room as Mitsuba scenes: the room alone, or with objects and probes added.

The room is triangulated and textured once (:func:`roomlight.datagen.synth.scene.scene_entries`); each
scene loads those same instantiated meshes and emitters with other shapes added, so staging a
photo and rendering its variants (photo, one scene per probe material, the oracle) rebuild no
geometry, only Mitsuba's acceleration structure.
"""

from __future__ import annotations

from roomlight.core.render.variant import mitsuba

__all__ = ["SceneSet", "RoomScenes"]


class SceneSet:
    """Instantiated Mitsuba entries (``entries``: the integrator, shapes and emitters of a set) that load
    as a scene with other shapes added. Subclasses fill ``entries`` and ``room`` (what the staging and
    the photo record read) and call :meth:`scene` once for ``base``."""

    entries: dict
    room: object

    def scene(self, extra: dict | None = None):
        """A ``mi.Scene`` of the set plus ``extra`` entries (shapes keyed by id)."""
        clash = sorted(set(extra or {}) & set(self.entries))
        if clash:
            raise KeyError(f"{type(self).__name__}: entries {clash} would replace the set's own")
        return mitsuba().load_dict({**self.entries, **(extra or {})})


class RoomScenes(SceneSet):
    """Scenes of one room (see the module docstring).

    Args:
        room: a :class:`~roomlight.datagen.synth.spec.Room`; max_depth: longest light path of the room's
            ``path`` integrator (no Russian roulette).
    Attributes:
        base: the room alone.
    """

    def __init__(self, room, max_depth: int = 5):
        from roomlight.datagen.synth.scene import scene_entries

        self.room = room
        self.entries = scene_entries(room, max_depth)
        self.base = self.scene()
