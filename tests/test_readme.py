"""The README's tour and Python snippets run exactly as written, in an empty folder.

The tour is the first ``bash`` block of "Five-minute tour"; it must start from files roomlight
makes itself. Every ``python`` block runs too, in order, in the same folder (so a snippet may use
what the tour wrote), except blocks preceded by a ``<!-- needs-user-data: ... -->`` line: those
need files only the reader has (a photographed scene, a trained prior).
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

README = Path(__file__).parents[1] / "README.md"
SRC = Path(__file__).parents[1] / "src"
FENCE = re.compile(r"(<!-- needs-user-data:[^\n]*-->\n)?```(\w+)\n(.*?)```", re.S)


def blocks(lang: str) -> list[tuple[str, bool]]:
    """(code, needs user data) of every ``lang`` block of the README."""
    return [(m.group(3), bool(m.group(1))) for m in FENCE.finditer(README.read_text()) if m.group(2) == lang]


def tour() -> str:
    text = README.read_text()
    section = text[text.index("## Five-minute tour"):]
    return next(m.group(3) for m in FENCE.finditer(section) if m.group(2) == "bash")


def environment() -> dict:
    bin_dir = str(Path(sys.executable).parent)
    return {**os.environ, "PATH": os.pathsep.join([bin_dir, os.environ.get("PATH", "")]),
            "PYTHONPATH": os.pathsep.join([str(SRC), os.environ.get("PYTHONPATH", "")]), "ROOMLIGHT_THREADS": "1"}


def test_the_tour_uses_no_file_the_reader_does_not_have():
    script = tour()
    assert "my_" not in script and ".venv" not in script
    made = set()
    for line in script.replace("\\\n", " ").splitlines():
        line = line.split("#")[0].strip()
        if not line:
            continue
        args = line.split()
        # every path a command reads was written by an earlier command of the tour
        for a in args[1:]:
            if "/" in a and not a.startswith("-"):
                top = a.split("/")[0]
                assert top in made or "--out" in line and args[args.index("--out") + 1] == a, (a, line)
        if "--out" in args:
            made.add(args[args.index("--out") + 1].split("/")[0])


def test_snippets_marked_as_needing_user_data_are_few():
    assert sum(needs for _, needs in blocks("python")) <= 1


@pytest.mark.slow
@pytest.mark.mitsuba
def test_readme_tour_and_python_snippets_run_as_written(tmp_path):
    env = environment()
    r = subprocess.run(["bash", "-euo", "pipefail", "-c", tour()], cwd=tmp_path, env=env, capture_output=True,
                       text=True, timeout=900)
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-3000:]
    assert (tmp_path / "out" / "render").is_dir() and (tmp_path / "out" / "room" / "scene.xml").is_file()
    ran = 0
    for i, (code, needs_data) in enumerate(blocks("python")):
        if needs_data:
            continue
        r = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=env, capture_output=True, text=True,
                           timeout=600)
        assert r.returncode == 0, f"python block {i}:\n{code}\n{r.stderr[-3000:]}"
        ran += 1
    assert ran >= 2
    assert (tmp_path / "out" / "brighter.exr").is_file()
