"""Recovering a room's light from images: scene descriptions, inverse rendering with every method,
the photo fit, and inserting objects into a fitted photograph.
"""
