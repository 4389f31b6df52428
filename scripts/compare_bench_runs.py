"""Two runs of a benchmark that differ by one setting, compared scene by scene with bootstrap intervals.

A synthetic benchmark (``roomlight bench run``) or a photo benchmark (``roomlight bench run-photos``)
was run twice on the same scenes, e.g. without and with the white balance. The second run's
methods are renamed ``<method><suffix>`` and each is paired with every method of the first run:
``METHOD+wb − baseline`` for each metric and material, as in the benchmark's own report (for a photo
benchmark also the recovered materials and the compositing scores of the inserted objects, paired per object
and per photo: a photo's objects share its fitted light, so only the second interval resamples independent
draws).

Either side may be several runs of the same setting with other fit seeds, joined by commas
(``results/a,results/a-seed1000``): each score is then the mean over those runs (scenes that any of them
lacks are left out), so the pairs compare what each setting gives on a scene, not one draw of it.

Run: .venv/bin/python scripts/compare_bench_runs.py BASE_RESULTS[,BASE2...] OTHER_RESULTS[,OTHER2...]
         [--suffix +wb] [--method prior] [--view eval] [--out FILE.md]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path


def _records(res: Path, suffix: str = "") -> tuple[list[dict], list[dict] | None, list[dict] | None]:
    """(probe or scene records, material records or None, inserted-object records or None) of a results folder."""
    if (res / "run.json").is_file() and json.loads((res / "run.json").read_text()).get("kind") == "photos":
        from roomlight.evaluation.photobench.report import (collect_photo_results, insertion_records, material_records,
                                                 probe_records)

        results = collect_photo_results(res)
        for r in results:
            r["method"] += suffix
        return probe_records(results), material_records(results), insertion_records(results)
    from roomlight.evaluation.bench.report import collect_results

    recs = collect_results(res)
    for r in recs:
        r["method"] += suffix
    return recs, None, None


def _mean_records(spec: str, suffix: str = "") -> tuple[list[dict], list[dict] | None, list[dict] | None]:
    """:func:`_records` of one results folder, or of several joined by commas averaged over them."""
    from roomlight.evaluation.harness.paired import mean_over_runs

    folders = [Path(p) for p in spec.split(",") if p]
    for f in folders:
        if not f.is_dir():
            sys.exit(f"error: {f} is not a results folder")
    if len({f.resolve() for f in folders}) < len(folders):
        sys.exit(f"error: {spec}: a run is given twice")
    runs = [_records(f, suffix) for f in folders]
    if len(runs) == 1:
        return runs[0]
    merged = []
    for part in range(3):
        lists = [r[part] for r in runs]
        merged.append(None if any(x is None for x in lists) else mean_over_runs(lists))
    return tuple(merged)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("base", help="a results folder, or several (other seeds) joined by commas")
    ap.add_argument("other", help="the same for the other setting")
    ap.add_argument("--suffix", default="+wb", help="appended to the second run's method names")
    ap.add_argument("--method", default="prior", help="the second run's method to compare (before the suffix)")
    ap.add_argument("--view", default="eval", help="synthetic benchmark view: eval (the probe) or input")
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args(argv)
    from roomlight.evaluation.harness.paired import paired_differences, paired_markdown
    from roomlight.errors import RoomlightError

    try:
        base, base_mat, base_ins = _mean_records(args.base)
        other, other_mat, other_ins = _mean_records(args.other, args.suffix)
    except RoomlightError as exc:
        sys.exit(f"error: {exc}")
    method = args.method + args.suffix
    view = args.view if base_mat is None else "eval"
    paired = paired_differences(base + other, method, view)
    md = [f"## {method} (from {args.other}) against each method of {args.base}, view {view}", "",
          paired_markdown(paired, method)]
    if base_mat is not None and other_mat is not None:
        from roomlight.evaluation.photobench.scoring import MATERIAL_METRICS

        higher = {k: False for k in MATERIAL_METRICS}
        pm = paired_differences(base_mat + other_mat, method, "materials", metrics=MATERIAL_METRICS,
                                higher_is_better=higher)
        md += ["## The recovered materials", "",
               paired_markdown(pm, method, ["objects"], {k: f"Δ {k}" for k in MATERIAL_METRICS}, note=False)]
    if base_ins and other_ins:
        from roomlight.evaluation.photobench.report import INSERT_LABELS, insert_metrics, paired_insertion

        pi, by_photo = paired_insertion(base_ins + other_ins, method)
        labels = {k: f"Δ {INSERT_LABELS[k]}" for k in insert_metrics(base_ins + other_ins)}
        md += ["", "## The inserted objects (paired per object)", "",
               paired_markdown(pi, method, ["objects"], labels, note=False),
               "", "## The inserted objects (paired per photo: its objects' differences averaged)", "",
               "A photo's objects share its fitted light, so their differences are not independent; this interval "
               "resamples photos.", "",
               paired_markdown(by_photo, method, ["objects"], labels, note=False)]
    text = "\n".join(md)
    print(text)
    if args.out:
        args.out.write_text(text + "\n")


if __name__ == "__main__":
    main()
