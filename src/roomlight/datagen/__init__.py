"""Making training data: procedural rooms rendered as panoramas, and real captures prepared.
"""
