"""Compare two ``roomlight eval-prior`` reports room by room, with bootstrap intervals.

Run: .venv/bin/python scripts/compare_prior_evals.py BASE.json OTHER.json
         [--row "latent fit"] [--other-row ROW] [--labels BASE_LABEL OTHER_LABEL] [--out FILE.md]

Both reports must have been made on the same panoramas (they are paired by file name). BASE and
OTHER may be the same file with different rows, e.g. --row encoder --other-row "latent fit".
Several reports joined by commas (A.json,B.json) are pooled, e.g. two evaluations of different room
folders; their panoramas must have distinct names.
"""

import argparse
import json
import sys
from pathlib import Path

from roomlight.errors import RoomlightError
from roomlight.prior.eval.compare import compare_reports, comparison_markdown


def _load(paths: str) -> dict:
    """One report, or several (comma-separated paths) pooled into one."""
    per_image, seen = [], set()
    for path in paths.split(","):
        try:
            report = json.loads(Path(path).read_text())
        except (OSError, ValueError) as exc:
            sys.exit(f"error: cannot read the report {path}: {exc}")
        for rec in report.get("per_image", []):
            if rec.get("name") in seen:
                sys.exit(f"error: {rec.get('name')} is in more than one of {paths}: pooled reports need distinct rooms")
            seen.add(rec.get("name"))
            per_image.append(rec)
    return {"per_image": per_image}


def main(argv=None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("base", help="eval_prior.json of the reference")
    p.add_argument("other", help="eval_prior.json to compare with it")
    p.add_argument("--row", default="latent fit", help="row of BASE (default: latent fit)")
    p.add_argument("--other-row", default=None, help="row of OTHER (default: the same as --row)")
    p.add_argument("--labels", nargs=2, default=None, metavar=("BASE", "OTHER"), help="column titles")
    p.add_argument("--out", default=None, help="also write the table to this Markdown file")
    args = p.parse_args(argv)
    try:
        cmp = compare_reports(_load(args.base), _load(args.other), args.row, args.other_row)
    except RoomlightError as exc:
        sys.exit(f"error: {exc}")
    labels = args.labels or (None, None)
    md = comparison_markdown(cmp, *labels)
    print(md, end="")
    if args.out:
        Path(args.out).write_text(md)


if __name__ == "__main__":
    main()
