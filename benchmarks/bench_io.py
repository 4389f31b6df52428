"""Speed of panorama I/O: reading and writing a 1024 x 2048 Radiance HDR file.

Prints a Markdown table of medians over repeated runs (first run excluded as warm-up). The image
mixes smooth content (literal runs in the RLE) with a constant band (repeat runs), as the I/O
tests do.
Run: .venv/bin/python benchmarks/bench_io.py [--repeats N]
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np
from bench_emitter import median_time  # this folder is on sys.path when a script in it runs


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()

    from roomlight.core.io import read_hdr, write_hdr

    rng = np.random.default_rng(1234)
    h, w = 1024, 2048
    v = np.linspace(0.0, 1.0, h)[:, None, None]
    rad = (0.2 + 2.0 * v * rng.random((1, w, 3))).astype(np.float32)
    rad[300:500] = 3.0
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "big.hdr"
        t_write = median_time(lambda: write_hdr(path, rad), args.repeats)
        t_read = median_time(lambda: read_hdr(path), args.repeats)
    print("| benchmark | value |")
    print("|---|---:|")
    print(f"| write_hdr {h}x{w} | {1e3 * t_write:.0f} ms |")
    print(f"| read_hdr {h}x{w} | {1e3 * t_read:.0f} ms |")


if __name__ == "__main__":
    main()
