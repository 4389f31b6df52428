"""Finding the panoramas of a dataset folder and splitting them into train / val / test.

Two layouts are understood:

- **split folders**: ``DIR/train``, ``DIR/val`` (and optionally ``DIR/test``) hold the files of
  each split (what ``roomlight synth`` writes);
- **one folder**: every panorama under ``DIR``; a file goes to the validation split when a hash
  of its relative path falls below ``val_fraction``. Hashing the *name* (not the position in a
  listing) keeps a file in the same split when other files are added or removed.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

from roomlight.errors import InputFileError

__all__ = ["PANORAMA_SUFFIXES", "SPLIT_NAMES", "find_panoramas", "has_split_folders", "split_files",
           "hash_fraction"]

#: Panorama files a folder is scanned for. Radiance ``.hdr`` files carry no depth: training skips
#: them by name, ``eval-prior --radiance-only`` uses them.
PANORAMA_SUFFIXES = (".exr", ".hdr")
#: Sub-folder names of the split layout.
SPLIT_NAMES = ("train", "val", "test")


def find_panoramas(root: str | Path) -> list[Path]:
    """All panorama files under ``root`` (recursively), sorted by relative path.

    Hidden files and folders (``.roomlight-cache`` and the like) are ignored.

    Raises:
        InputFileError: ``root`` is not a directory.
    """
    root = Path(root)
    if not root.is_dir():
        raise InputFileError(root, "is not a directory", "pass a folder of panorama EXRs")
    files = []
    for p in root.rglob("*"):
        rel = p.relative_to(root)
        if any(part.startswith(".") for part in rel.parts):
            continue
        if p.is_file() and p.suffix.lower() in PANORAMA_SUFFIXES:
            files.append(p)
    return sorted(files, key=lambda p: p.relative_to(root).as_posix())


def has_split_folders(root: str | Path) -> bool:
    """True when ``root`` has a ``train`` sub-folder (the split-folder layout)."""
    return (Path(root) / "train").is_dir()


def hash_fraction(name: str) -> float:
    """Deterministic pseudo-random number in [0, 1) from a file's relative path."""
    digest = hashlib.sha1(name.encode("utf-8")).digest()
    return int.from_bytes(digest[:8], "big") / 2.0**64


def split_files(root: str | Path, val_fraction: float = 0.05) -> dict[str, list[Path]]:
    """Files of each split: ``{"train": [...], "val": [...], "test": [...]}``.

    With split folders, each list holds that folder's panoramas (``test`` may be empty). With one
    folder, ``test`` is empty and ``val`` gets the files whose :func:`hash_fraction` of the
    relative path is below ``val_fraction`` (expected share ``val_fraction``).

    Raises:
        InputFileError: no panorama at all under ``root``.
    """
    root = Path(root)
    if has_split_folders(root):
        out = {name: find_panoramas(root / name) if (root / name).is_dir() else [] for name in SPLIT_NAMES}
    else:
        files = find_panoramas(root)
        val = [p for p in files if hash_fraction(p.relative_to(root).as_posix()) < val_fraction]
        val_set = set(val)
        out = {"train": [p for p in files if p not in val_set], "val": val, "test": []}
    if not any(out.values()):
        raise InputFileError(root, "contains no panorama (.exr) files",
                             "expected a folder of R,G,B,Z (or R,G,B,A) EXR panoramas")
    return out
