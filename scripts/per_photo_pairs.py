"""One method of two photo-benchmark runs side by side, photo by photo: each probe material's PSNR LDR in
both runs and their difference, the inserted objects' region PSNR (mean over the photo's objects), and
the photo's kind (procedural room or captured light; the wide suite's rooms say which rare draw they are).

The paired means and intervals are compare_bench_runs.py's; this table says *which* photos move.

Run: .venv/bin/python scripts/per_photo_pairs.py BASE_RESULTS OTHER_RESULTS [--method prior]
         [--bench BENCH] [--names base,other] [--out FILE.md]
"""

from __future__ import annotations

import argparse
import json
import sys
from collections import defaultdict
from pathlib import Path

MATERIALS = ("diffuse", "matte", "mirror")


def _scores(res: Path, method: str) -> dict[str, dict[str, float]]:
    """photo -> {material or 'inserted': PSNR LDR} of ``method`` in a results folder."""
    from roomlight.evaluation.photobench.report import collect_photo_results, insertion_records, probe_records

    results = [r for r in collect_photo_results(res) if r["method"] == method]
    out: dict[str, dict[str, float]] = defaultdict(dict)
    for r in probe_records(results):
        out[r["scene"]][r["material"]] = r["metrics"]["eval"]["psnr_ldr"]
    ins: dict[str, list[float]] = defaultdict(list)
    for r in insertion_records(results):
        ins[r["scene"].split("/")[0]].append(r["metrics"]["insert"]["psnr_ldr"])
    for photo, values in ins.items():
        out[photo]["inserted"] = sum(values) / len(values)
    return out


def _kind(bench: Path | None, photo: str) -> str:
    """What the photo is, from its truth record: the captured panorama it is lit by, or the room's kind."""
    if bench is None:
        return ""
    rec = bench / photo / "truth" / "photo.json"
    if not rec.is_file():
        return ""
    d = json.loads(rec.read_text())
    if d.get("captured"):
        return f"captured: {d['captured'].get('light', '?')}"
    plan = d.get("plan") or {}
    return f"room: {plan['room_kind']}" if plan.get("room_kind") else "room"


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("base", type=Path)
    ap.add_argument("other", type=Path)
    ap.add_argument("--method", default="prior")
    ap.add_argument("--bench", type=Path, default=None, help="the bench folder, to say what each photo is")
    ap.add_argument("--names", default="base,other", help="the two runs' names in the header")
    ap.add_argument("--out", type=Path, default=None)
    a = ap.parse_args(argv)
    base, other = _scores(a.base, a.method), _scores(a.other, a.method)
    names = a.names.split(",")
    photos = sorted(set(base) & set(other))
    if not photos:
        sys.exit(f"error: {a.base} and {a.other} share no photo fitted with {a.method}")
    cols = [*MATERIALS, "inserted"]
    lines = [f"| photo | kind | " + " | ".join(f"{c}: {names[0]} / {names[1]} / diff" for c in cols) + " |",
             "|---|---|" + ":---:|" * len(cols)]
    sums: dict[str, list[float]] = defaultdict(list)
    for p in photos:
        cells = []
        for c in cols:
            b, o = base[p].get(c), other[p].get(c)
            if b is None or o is None:
                cells.append("")
                continue
            sums[c].append(o - b)
            cells.append(f"{b:.2f} / {o:.2f} / {o - b:+.2f}")
        lines.append(f"| {p} | {_kind(a.bench, p)} | " + " | ".join(cells) + " |")
    lines.append("| **mean difference** | | " + " | ".join(
        f"{sum(sums[c]) / len(sums[c]):+.2f} ({sum(d > 0 for d in sums[c])}/{len(sums[c])} up)" if sums[c] else ""
        for c in cols) + " |")
    text = "\n".join(lines) + "\n"
    if a.out:
        a.out.write_text(text)
    print(text, end="")


if __name__ == "__main__":
    main()
