"""Paired comparison of two prior evaluations (``roomlight eval-prior`` reports), room by room.

Two rows evaluated on the same panoramas — two priors, or two latent-fit objectives of one prior —
differ by less than the spread between rooms, so their means alone cannot say which is better.
Rooms are paired by file name; for each metric the report gives both means, the mean of the
per-room difference ``other - base`` with a 95 % percentile-bootstrap interval
(:func:`roomlight.core.stats.bootstrap_mean_interval`), and the number of rooms where ``other`` is
strictly better.
"""

from __future__ import annotations

import math

from roomlight.errors import RoomlightError
from roomlight.prior.eval.prior import METRICS, metric_digits
from roomlight.core.stats import RESAMPLES, VERDICT_MARKS, bootstrap_mean_interval, interval_verdict

__all__ = ["compare_reports", "comparison_markdown"]


def _values(report: dict, row: str, what: str) -> dict[str, dict]:
    """name -> metrics of ``row`` for every panorama of ``report`` that has that row."""
    out = {rec["name"]: rec[row] for rec in report.get("per_image", []) if row in rec}
    if not out:
        rows = sorted({k for rec in report.get("per_image", []) for k in rec if k != "name"})
        raise RoomlightError(f"{what}: no per-image values for row {row!r} (rows: {', '.join(rows) or 'none'})")
    return out


def _finite(value) -> bool:
    """A metric value that can enter a mean (JSON reports write NaN and inf as null)."""
    return value is not None and math.isfinite(value)


def compare_reports(base: dict, other: dict, base_row: str = "latent fit", other_row: str | None = None) -> dict:
    """Per-metric paired statistics of ``other`` against ``base``.

    Args:
        base, other: eval-prior reports (the dicts :func:`roomlight.prior.eval.evaluate_prior` returns,
            or their JSON files loaded).
        base_row, other_row: which row of each (``other_row`` defaults to ``base_row``).
    Returns:
        ``{"n": rooms paired, "base": label, "other": label, "metrics": {metric: stats}}`` where
        ``stats`` holds ``base`` and ``other`` (means over the paired rooms; ``base_ci95`` and
        ``other_ci95`` their bootstrap intervals, to read a mean against a target), ``diff`` (mean of
        other - base), ``ci95``, ``wins`` (rooms where other is strictly better), ``n`` and
        ``better`` ("higher" or "lower"). Rooms where either value is missing or not finite are
        left out of that metric.
    """
    other_row = other_row or base_row
    a = _values(base, base_row, "base report")
    b = _values(other, other_row, "other report")
    names = [n for n in a if n in b]
    if not names:
        raise RoomlightError("the two reports share no panorama (they are paired by file name)")
    metrics = {}
    for key, (_, higher) in METRICS.items():
        pairs = [(a[n][key], b[n][key]) for n in names if _finite(a[n].get(key)) and _finite(b[n].get(key))]
        if not pairs:
            continue
        diffs = [y - x for x, y in pairs]
        lo, hi = bootstrap_mean_interval(diffs)
        metrics[key] = {
            "base": sum(x for x, _ in pairs) / len(pairs), "other": sum(y for _, y in pairs) / len(pairs),
            "base_ci95": list(bootstrap_mean_interval([x for x, _ in pairs])),
            "other_ci95": list(bootstrap_mean_interval([y for _, y in pairs])),
            "diff": sum(diffs) / len(diffs), "ci95": [lo, hi], "n": len(pairs),
            "wins": sum((d > 0) if higher else (d < 0) for d in diffs),
            "better": "higher" if higher else "lower",
        }
    return {"n": len(names), "base": base_row, "other": other_row, "metrics": metrics}


def comparison_markdown(comparison: dict, base_label: str | None = None, other_label: str | None = None) -> str:
    """The comparison as a Markdown table, one line per metric."""
    base_label = base_label or comparison["base"]
    other_label = other_label or comparison["other"]
    lines = [f"{comparison['n']} rooms paired by name; difference = {other_label} − {base_label}.", "",
             f"| metric | {base_label} | {other_label} | difference [95 % interval] | {other_label} better |",
             "|---|---:|---:|---|---:|"]
    for key, s in comparison["metrics"].items():
        digits = metric_digits(key)
        lo, hi = s["ci95"]
        mark = VERDICT_MARKS[interval_verdict(lo, hi, s["n"], s["better"] == "higher")]
        base = f"{s['base']:.{digits}f} [{s['base_ci95'][0]:.{digits}f}, {s['base_ci95'][1]:.{digits}f}]"
        other = f"{s['other']:.{digits}f} [{s['other_ci95'][0]:.{digits}f}, {s['other_ci95'][1]:.{digits}f}]"
        lines.append(f"| {METRICS[key][0]} | {base} | {other} | "
                     f"{s['diff']:+.{digits}f} [{lo:+.{digits}f}, {hi:+.{digits}f}]{mark} | {s['wins']}/{s['n']} |")
    lines += ["", f"Means and the mean difference with 95 % percentile-bootstrap intervals ({RESAMPLES} resamples "
              f"of the rooms); ✓ difference entirely on the good side, ✗ entirely on the bad side."]
    return "\n".join(lines) + "\n"
