"""Procedural indoor rooms: generator (rooms, furniture, lights, sky), Mitsuba scenes, panorama rendering, dataset driver."""
