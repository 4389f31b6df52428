"""The foundations every step stands on: panorama geometry and files, the 2.5D light and its emitter
forms, rendering, colour, settings, progress, threads and statistics.
"""
