"""Statistics shared by every comparison roomlight reports (benchmarks, ablations, prior evaluations).

A mean over a handful of scenes or rooms hides how sure we are of it; every comparison therefore
reports a percentile-bootstrap interval of the mean (of a per-item difference, when two methods
were run on the same items).
"""

from __future__ import annotations

import numpy as np

__all__ = ["RESAMPLES", "VERDICT_MARKS", "bootstrap_mean_interval", "bootstrap_slope_interval", "interval_verdict"]

#: Number of bootstrap resamples (the interval's Monte Carlo error is ~0.5 % of its width).
RESAMPLES = 10000


def bootstrap_mean_interval(values, level: float = 0.95, resamples: int = RESAMPLES,
                            seed: int = 0) -> tuple[float, float]:
    """Percentile-bootstrap interval of the mean of ``values`` (1-D, finite).

    Resamples the values with replacement ``resamples`` times (seeded, so a report is
    reproducible) and returns the (1 - level)/2 and (1 + level)/2 quantiles of the resampled
    means. With one value the interval is that value; with none, (nan, nan).
    """
    a = np.asarray(values, np.float64)
    if a.size == 0:
        return float("nan"), float("nan")
    if a.size == 1:
        return float(a[0]), float(a[0])
    rng = np.random.default_rng(seed)
    means = a[rng.integers(0, a.size, size=(resamples, a.size))].mean(axis=1)
    lo, hi = np.quantile(means, [(1.0 - level) / 2.0, (1.0 + level) / 2.0])
    return float(lo), float(hi)


def bootstrap_slope_interval(x, y, level: float = 0.95, resamples: int = 2000,
                             seed: int = 0, clusters=None) -> tuple[float, float, float]:
    """Least-squares slope of ``y`` over ``x`` (1-D, finite, same length) and its percentile-bootstrap interval:
    (slope, lo, hi), in units of y per unit of x.

    Pairs (x, y) are resampled with replacement; with ``clusters`` (one label per pair, e.g. the photo
    an inserted object stands in, whose objects share one fitted light and so are not independent) whole
    clusters are resampled instead, each with all its pairs (fewer than two clusters: no interval, nan).
    A resample whose x are all equal has no slope and is skipped. Without two distinct x the slope is nan,
    and so is the interval when no resample has one.
    """
    x, y = np.asarray(x, np.float64), np.asarray(y, np.float64)
    if x.size < 2 or np.ptp(x) == 0:
        return float("nan"), float("nan"), float("nan")
    slope = float(np.polyfit(x, y, 1)[0])
    groups = None
    if clusters is not None:
        clusters = list(clusters)
        if len(clusters) != x.size:
            raise ValueError(f"clusters: one label per pair expected, got {len(clusters)} for {x.size} pairs")
        members: dict = {}
        for k, c in enumerate(clusters):  # first appearance order; any hashable label
            members.setdefault(c, []).append(k)
        if len(members) < 2:
            return slope, float("nan"), float("nan")
        groups = [np.array(v) for v in members.values()]
    rng = np.random.default_rng(seed)
    boots = []
    for _ in range(resamples):
        if groups is None:
            i = rng.integers(0, x.size, x.size)
        else:
            i = np.concatenate([groups[g] for g in rng.integers(0, len(groups), len(groups))])
        if np.ptp(x[i]) > 0:
            boots.append(np.polyfit(x[i], y[i], 1)[0])
    if not boots:
        return slope, float("nan"), float("nan")
    # rounded so that level 0.95 asks for exactly the 2.5th and 97.5th percentiles
    lo, hi = np.percentile(boots, [round(50.0 * (1.0 - level), 10), round(50.0 * (1.0 + level), 10)])
    return slope, float(lo), float(hi)


#: How tables mark a :func:`interval_verdict`.
VERDICT_MARKS = {1: " ✓", -1: " ✗", 0: ""}


def interval_verdict(lo: float, hi: float, n: int, higher_is_better: bool) -> int:
    """Which side of zero a difference's interval [lo, hi] lies on, read as better or worse.

    Returns 1 when the whole interval is on the good side (above zero when higher is better, below
    when lower is), -1 when it is wholly on the bad side, 0 otherwise. One item gives a zero-width
    interval that decides nothing, so ``n`` < 2 is always 0.
    """
    if n < 2:
        return 0
    good, bad = (lo > 0, hi < 0) if higher_is_better else (hi < 0, lo > 0)
    return 1 if good else -1 if bad else 0
