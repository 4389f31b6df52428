"""One procedural room as Mitsuba scenes: the room alone, or with objects and probes added.

The room is triangulated and textured once (:func:`roomlight.datagen.synth.scene.scene_entries`); each
scene loads those same instantiated meshes and emitters with other shapes added, so staging a
photo and rendering its variants (photo, one scene per probe material, the oracle) rebuild no
geometry, only Mitsuba's acceleration structure.
"""

from __future__ import annotations

from roomlight.core.render.variant import mitsuba

__all__ = ["RoomScenes"]


class RoomScenes:
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

    def scene(self, extra: dict | None = None):
        """A ``mi.Scene`` of the room plus ``extra`` entries (shapes keyed by id)."""
        clash = sorted(set(extra or {}) & set(self.entries))
        if clash:
            raise KeyError(f"RoomScenes: entries {clash} would replace the room's own")
        return mitsuba().load_dict({**self.entries, **(extra or {})})
