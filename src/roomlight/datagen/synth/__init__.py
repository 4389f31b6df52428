"""Procedural indoor rooms: generator (rooms, furniture, lights, sky), Mitsuba scenes, panorama rendering, dataset driver."""

from __future__ import annotations

from roomlight.datagen.synth.dataset import SynthConfig, contact_sheet, generate_dataset, render_room

__all__ = ["SynthConfig", "contact_sheet", "generate_dataset", "render_room"]
