"""benchmarks/insertion_diagnosis.py's paired statistics: per object, and per photo with each photo's
objects' differences averaged first (hand-computed values)."""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path

import numpy as np
import pytest

SCRIPT = Path(__file__).resolve().parents[1] / "benchmarks" / "insertion_diagnosis.py"


def _module():
    spec = importlib.util.spec_from_file_location("insertion_diagnosis", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _records():
    """Photo p1: two objects, oracle − oracle-envmap +3 and +1 on objects; photo p2: one object, −1;
    photo p3: one object, +2 (and a non-finite shadow score, left out)."""
    rows = [("p1", "insert1", 3.0), ("p1", "insert2", 1.0), ("p2", "insert1", -1.0), ("p3", "insert1", 2.0)]
    out = []
    for k, (photo, oid, diff) in enumerate(rows):
        for variant, value in (("oracle", 20.0 + diff), ("oracle-envmap", 20.0)):
            out.append({"photo": photo, "id": oid, "variant": variant, "distance_m": 1.0 + k,
                        "psnr_ldr": value, "object_psnr_ldr": value,
                        "shadow_psnr_ldr": float("nan") if photo == "p3" else value})
    return out


def test_paired_per_object_and_per_photo():
    mod = _module()
    recs = _records()
    mean, lo, hi, wins, n = mod.paired(recs, "oracle", "oracle-envmap", "object_psnr_ldr")
    assert (mean, wins, n) == (pytest.approx(1.25), 3, 4)            # (3 + 1 − 1 + 2) / 4
    mean, lo, hi, wins, n = mod.paired(recs, "oracle", "oracle-envmap", "object_psnr_ldr", by_photo=True)
    assert (mean, wins, n) == (pytest.approx(1.0), 2, 3)             # photos: 2, −1, 2
    assert -1.0 <= lo <= 1.0 <= hi <= 2.0
    # a photo whose only object has a non-finite score drops out of the per-photo pairing
    assert mod.paired(recs, "oracle", "oracle-envmap", "shadow_psnr_ldr", by_photo=True)[4] == 2
    # the photo means 2, -1, 2 resampled three at a time: the mean is 2 - k with k ~ Binomial(3, 1/3) draws of
    # the -1, so P(mean = -1) = 1/27 = 3.7 % > 2.5 % and P(mean = 2) = 8/27 > 2.5 %: the interval is [-1, 2]
    assert (lo, hi) == (-1.0, 2.0)


def test_the_table_prints_both_pairings():
    mod = _module()
    text = mod.table(_records())
    assert "| oracle − oracle-envmap | +1.25 [" in text
    per_photo = text.split("paired per photo")[1]
    assert "| oracle − oracle-envmap | +1.00 [" in per_photo and " 2/3 |" in per_photo
    # objects all at one distance: no slope to fit, the row says so instead of failing
    same = [{**r, "distance_m": 2.0} for r in _records()]
    row = next(line for line in mod.distance_table(same, [("oracle", "oracle-envmap")]).splitlines()
               if "object_psnr_ldr" in line)
    cells = [c.strip() for c in row.strip("|").split("|")]
    assert cells[2].startswith("+1.25") and cells[-2:] == ["–", "–"]   # all "near"; both slope columns empty


def test_fitted_lights_are_also_averaged_over_runs():
    """Two runs (fit seeds) of prior and prior-envmap: each object's scores averaged per method, a score one
    run lacks or has non-finite left as nan, the references untouched, and the averaged pair printed."""
    mod = _module()
    recs = []
    for run, shift in (("seed0", 0.0), ("seed1000", 2.0)):
        for method, base in (("prior", 21.0), ("prior-envmap", 20.0)):
            for oid in ("insert1", "insert2"):
                recs.append({"photo": "p1", "id": oid, "variant": f"{method} ({run})", "distance_m": 1.0,
                             "psnr_ldr": base + shift, "object_psnr_ldr": base + shift,
                             "shadow_psnr_ldr": float("nan") if (run, oid) == ("seed1000", "insert2") else base})
    recs.append({"photo": "p1", "id": "insert1", "variant": "oracle", "distance_m": 1.0,
                 "psnr_ldr": 30.0, "object_psnr_ldr": 30.0, "shadow_psnr_ldr": 30.0})
    out = mod.mean_over_runs(recs, ["seed0", "seed1000"])
    mean = {(r["variant"], r["id"]): r for r in out if "mean of 2 runs" in r["variant"]}
    assert mean[("prior (mean of 2 runs)", "insert1")]["psnr_ldr"] == 22.0          # (21 + 23) / 2
    assert mean[("prior-envmap (mean of 2 runs)", "insert2")]["object_psnr_ldr"] == 21.0
    assert math.isnan(mean[("prior (mean of 2 runs)", "insert2")]["shadow_psnr_ldr"])
    assert len(mean) == 4 and sum(r["variant"] == "oracle" for r in out) == 1
    assert "| prior (mean of 2 runs) − prior-envmap (mean of 2 runs) | +1.00 [" in mod.table(out)
    assert mod.mean_over_runs(recs, ["seed0"]) == recs
