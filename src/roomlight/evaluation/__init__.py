"""Measuring methods on benchmarks: the one harness every benchmark kind plugs into (``harness``), the
synthetic benchmark of the paper (``bench``), the photo benchmark (``photobench``) and the paper's
supplementary analyses (``experiments``).
"""
