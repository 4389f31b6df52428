"""A packed cache of a dataset at the training resolution, for fast loading.

Decoding EXRs and resampling them costs far more than a training step of a small model, so the
panoramas are decoded once into one array ``(N, 4, H, W)`` of (log1p R, G, B, log D) in
float16 (or float32), stored as ``.npy`` and memory-mapped by every data-loader worker, plus a
JSON manifest. Files that could not be decoded are listed in the manifest with the reason and
have no row.

The manifest records each file's size and modification time; a cache whose files changed is
rebuilt. Both files are written to temporary names and moved into place with ``os.replace``,
so an interrupted build never leaves a cache that looks valid.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import torch

from roomlight.errors import RoomlightError

__all__ = ["PackedCache", "CACHE_DIRNAME", "default_cache_path"]

CACHE_DIRNAME = ".roomlight-cache"
FORMAT = "roomlight.pack"
VERSION = 1


def default_cache_path(root: str | Path, resolution, dtype: str, calibrate: bool, depth_units: str) -> Path:
    """``ROOT/.roomlight-cache/pack-HxW-DTYPE-CAL-UNITS.npy``: one pack per loading setting."""
    h, w = resolution
    cal = "cal" if calibrate else "raw"
    return Path(root) / CACHE_DIRNAME / f"pack-{h}x{w}-{dtype}-{cal}-{depth_units}.npy"


def _identity(item):
    return item


def _fingerprint(path: Path) -> dict:
    st = path.stat()
    return {"size": st.st_size, "mtime_ns": st.st_mtime_ns}


class PackedCache:
    """Read access to a built pack. Use :meth:`open_or_build`.

    Attributes:
        resolution: (H, W) of the stored panoramas.
        manifest: the JSON manifest (``files``: name, size, mtime_ns, row or None, error).
    """

    def __init__(self, path: str | Path):
        self.path = Path(path)
        self.manifest = json.loads(self.path.with_suffix(".json").read_text())
        self.resolution = tuple(self.manifest["resolution"])
        self._rows = {f["name"]: f for f in self.manifest["files"]}
        self._array = None  # opened lazily, so that each data-loader worker maps its own view

    def __getstate__(self) -> dict:
        # Worker processes started with "spawn" receive a pickled copy: send the path, not the
        # mapped array (each worker maps the file itself).
        return {**self.__dict__, "_array": None}

    @property
    def errors(self) -> dict[str, str]:
        """name -> reason for every file that could not be packed."""
        return {f["name"]: f["error"] for f in self.manifest["files"] if f.get("error")}

    def __contains__(self, name: str) -> bool:
        return name in self._rows

    def get(self, name: str) -> torch.Tensor:
        """Encoded (4, H, W) float32 (log1p RGB, log depth) of file ``name`` (relative path).

        Raises:
            RoomlightError: the file is not in the cache or could not be decoded when packing
                (the message gives the original reason).
        """
        entry = self._rows.get(name)
        if entry is None:
            raise RoomlightError(f"{name}: not in the cache {self.path} (rebuild it)")
        if entry.get("row") is None:
            raise RoomlightError(entry.get("error") or f"{name}: not decodable")
        if self._array is None:
            self._array = np.load(self.path, mmap_mode="r")
        return torch.from_numpy(np.array(self._array[entry["row"]], dtype=np.float32))

    # ------------------------------------------------------------------ building
    @classmethod
    def is_current(cls, path: str | Path, root: Path, files: list[Path], settings: dict) -> bool:
        """True when the pack at ``path`` exists, has ``settings`` and covers ``files`` unchanged."""
        path = Path(path)
        mpath = path.with_suffix(".json")
        if not (path.exists() and mpath.exists()):
            return False
        try:
            m = json.loads(mpath.read_text())
        except (OSError, json.JSONDecodeError):
            return False
        if m.get("format") != FORMAT or m.get("version") != VERSION:
            return False
        if any(m.get(k) != v for k, v in settings.items()):
            return False
        entries = {f["name"]: f for f in m.get("files", [])}
        for p in files:
            e = entries.get(p.relative_to(root).as_posix())
            if e is None or {"size": e["size"], "mtime_ns": e["mtime_ns"]} != _fingerprint(p):
                return False
        return True

    @classmethod
    def open_or_build(cls, root: str | Path, files: list[Path], resolution, *, path: str | Path | None = None,
                      dtype: str = "float16", calibrate: bool = True, depth_units: str = "metres",
                      workers: int = 0, progress: bool = True, log=print, clamp_negative: bool = False,
                      fill_nonfinite: float | None = None) -> "PackedCache":
        """Open the pack for ``files`` (paths under ``root``), building it first if needed.

        Args:
            root: dataset folder; names in the manifest are relative to it.
            files: the panoramas to pack (typically every split).
            resolution: (H, W) training resolution.
            path: where the ``.npy`` goes (default :func:`default_cache_path`); its manifest is
                the same name with ``.json``.
            dtype: ``float16`` (half the size; ~0.4 % relative precision at the brightest
                pixels) or ``float32``.
            workers: processes decoding EXRs in parallel while building.
            log: function receiving one-line messages (e.g. skipped files).
            clamp_negative, fill_nonfinite: repairs, as for :func:`roomlight.prior.data.load_training_pair`
                (files needing one that is not enabled are skipped, with the reason).
        """
        root = Path(root)
        if dtype not in ("float16", "float32"):
            raise RoomlightError(f"cache dtype must be float16 or float32, got {dtype!r}")
        resolution = (int(resolution[0]), int(resolution[1]))
        path = Path(path) if path is not None else default_cache_path(root, resolution, dtype, calibrate, depth_units)
        settings = {"resolution": list(resolution), "dtype": dtype, "calibrate": calibrate,
                    "depth_units": depth_units, "encoding": "log1p_rgb_log_depth"}
        repairs = {"clamp_negative": clamp_negative, "fill_nonfinite": fill_nonfinite}
        if clamp_negative or fill_nonfinite is not None:  # recorded only when used: older packs stay current
            settings["repairs"] = repairs
        if not cls.is_current(path, root, files, settings):
            cls._build(path, root, files, resolution, settings, workers, progress, log)
        return cls(path)

    @classmethod
    def _build(cls, path: Path, root: Path, files: list[Path], resolution, settings: dict, workers: int,
               progress: bool, log) -> None:
        from torch.utils.data import DataLoader
        from roomlight.core.progress import progress_bar

        from roomlight.prior.data.dataset import PanoramaDataset, encode_pair

        path.parent.mkdir(parents=True, exist_ok=True)
        h, w = resolution
        n = len(files)
        tmp = path.with_name(path.stem + f".tmp-{os.getpid()}.npy")
        arr = np.lib.format.open_memmap(tmp, mode="w+", dtype=np.dtype(settings["dtype"]),
                                        shape=(max(n, 1), 4, h, w))
        repairs = settings.get("repairs", {})
        ds = PanoramaDataset(files, resolution, root=root, calibrate=settings["calibrate"],
                             depth_units=settings["depth_units"], clamp_negative=repairs.get("clamp_negative", False),
                             fill_nonfinite=repairs.get("fill_nonfinite"))
        # batch_size=None: items one by one, decoded in `workers` processes (EXR decoding is the cost).
        loader = DataLoader(ds, batch_size=None, shuffle=False, num_workers=workers,
                            collate_fn=_identity)
        entries, row = [], 0
        bar = progress_bar(loader, total=n, desc=f"packing {root.name} at {h}x{w}", unit="pano", disable=not progress)
        for item in bar:
            p = files[item["index"]]
            entry = {"name": item["name"], **_fingerprint(p), "row": None, "error": None}
            if "error" in item:
                entry["error"] = item["error"]
                log(f"skipping {item['name']}: {item['error']}")
            else:
                for fix in item.get("fixes", []):
                    log(f"note: {fix}")
                arr[row] = encode_pair(item["radiance"], item["depth"]).numpy().astype(arr.dtype)
                entry["row"] = row
                row += 1
            entries.append(entry)
        arr.flush()
        del arr
        manifest = {"format": FORMAT, "version": VERSION, **settings, "count": row, "files": entries}
        mtmp = path.with_name(path.stem + f".tmp-{os.getpid()}.json")
        mtmp.write_text(json.dumps(manifest, indent=1))
        # Old manifest out, data in, new manifest in: a crash in between leaves no manifest,
        # which fails is_current() and triggers a rebuild (never an old manifest over new rows).
        path.with_suffix(".json").unlink(missing_ok=True)
        os.replace(tmp, path)
        os.replace(mtmp, path.with_suffix(".json"))
