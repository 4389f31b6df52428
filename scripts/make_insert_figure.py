"""README's insertion figure (docs/images/insert-example.png): the rendered example photo, two objects
inserted under the light `fit-photo --preset fast` recovers from it, and the shadow ratio.

Run: .venv/bin/python scripts/make_insert_figure.py [--work DIR]     (about 2 minutes on 2 cores)
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
PLACEMENTS = [{"object": "blob", "at": [75, 195], "material": "diffuse:0.8,0.2,0.15"},
              {"object": "sphere", "at": [255, 175], "material": "mirror"}]


def main(argv=None) -> None:
    from PIL import Image

    from roomlight.fitting.photo.synthetic import example_photo_case

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--work", type=Path, default=ROOT / "results" / "insert-figure")
    args = ap.parse_args(argv)
    case, fit, ins = args.work / "case", args.work / "fit", args.work / "insert"
    if not (case / "camera.json").is_file():
        example_photo_case(str(case))
    roomlight = [sys.executable, "-m", "roomlight.cli.main"]
    if not (fit / "result.json").is_file():
        subprocess.run([*roomlight, "fit-photo", str(case), "--out", str(fit), "--preset", "fast", "--quiet"], check=True)
    places = args.work / "objects.json"
    places.write_text(json.dumps(PLACEMENTS))
    subprocess.run([*roomlight, "insert", str(fit), "--placements", str(places), "--out", str(ins / "composite.png")],
                   check=True)
    panels = [Image.open(case / "preview.png").convert("RGB"), Image.open(ins / "composite.png").convert("RGB"),
              Image.open(ins / "shadow.png").convert("RGB")]
    h = min(p.height for p in panels)
    panels = [p.resize((round(p.width * h / p.height), h)) for p in panels]
    gap = 4
    out = Image.new("RGB", (sum(p.width for p in panels) + gap * (len(panels) - 1), h), (40, 40, 40))
    x = 0
    for p in panels:
        out.paste(p, (x, 0))
        x += p.width + gap
    target = ROOT / "docs" / "images" / "insert-example.png"
    out.save(target, optimize=True)
    info = json.loads((ins / "insert.json").read_text())
    print(f"{target}: {out.width}x{out.height}; insert took {info['timings_s']['total']:.0f} s; "
          f"light pushed behind the scene on {100 * info['light_enclosing_scene']['texels_moved']:.1f} % of its texels")


if __name__ == "__main__":
    main()
