"""Headless Chromium (the Debian package) for the page tests: screenshots of local HTML files."""

from __future__ import annotations

import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np
import pytest

FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--enable-unsafe-swiftshader", "--use-angle=swiftshader", "--force-device-scale-factor=1",
         "--hide-scrollbars", "--mute-audio"]


def chromium() -> str:
    """The Chromium binary, or skip the test with the reason and the fix."""
    for name in ("chromium", "chromium-browser", "/usr/bin/chromium"):
        path = shutil.which(name)
        if path:
            return path
    pytest.skip("Chromium is not installed ('make setup' installs the Debian package 'chromium'; "
                "on other systems install Chromium and put it on PATH)")


def screenshot(page: Path, out: Path, fragment: str = "", size=(800, 500), budget_ms: int = 300) -> np.ndarray:
    """Load ``page`` (with ``#fragment``) in a fresh profile and return the screenshot as (H, W, 3) uint8.

    ``budget_ms`` is Chromium's virtual time: the viewer draws the same still scene at every animation
    frame (60 per virtual second), each in software (SwiftShader), so a longer budget only repeats that
    frame; 900 ms and 300 ms give identical screenshots of a photo fit's page (the viewer test of
    tests/test_insert.py took 42 s with the former, 15 s with the latter)."""
    from PIL import Image

    with tempfile.TemporaryDirectory() as profile:
        cmd = [chromium(), *FLAGS, f"--user-data-dir={profile}", f"--window-size={size[0]},{size[1]}",
               f"--virtual-time-budget={budget_ms}", f"--screenshot={out}",
               page.resolve().as_uri() + (f"#{fragment}" if fragment else "")]
        res = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert out.is_file(), f"chromium wrote no screenshot (exit {res.returncode}):\n{res.stderr[-2000:]}"
    return np.asarray(Image.open(out).convert("RGB"))
