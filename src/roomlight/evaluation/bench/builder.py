"""``roomlight bench make``: the synthetic benchmark from a folder of radiance + depth panoramas.

Per panorama (the paper's protocol, see :mod:`roomlight.evaluation.bench.placement`) and per material,
one scene directory ``BENCH/<panorama>/<material>/`` holding

============================  ==================================================================
``scene.json``                the scene description (relative paths; views ``input`` and ``eval``)
``emitter.exr``               the ground-truth emitter: R, G, B (x the camera exposure) + Z (metres)
``input.exr``, ``eval.exr``   linear HDR renders (float32) of the two views at ``spp``
``input.png``, ``eval.png``   8-bit gamma-2.2 recordings, saturating above 1
``input_mask.png``, ...       object pixels (255): pixels fully covered by the view's objects
============================  ==================================================================

plus ``BENCH/<panorama>/panorama.json`` (placement record; marks the panorama as done, so an
interrupted build resumes) and ``BENCH/manifest.json`` listing every scene.

Exposure (:mod:`roomlight.evaluation.bench.recording`): k = 0.18 / log-average luminance of the input
view's object pixels, per panorama and material; it is baked into the emitter and both renders.
"""

from __future__ import annotations

import json
import re
import shutil
import zlib
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import torch

from roomlight.evaluation.harness.errors import BenchError
from roomlight.core.config import StrictConfig
from roomlight.evaluation.bench.placement import (
    STRATA,
    EmitterProbe,
    PlacementConfig,
    place_objects,
)
from roomlight.evaluation.bench.recording import (
    EXPOSURE_KEY,
    exposure_for,
    record_ldr,
    saturated_fraction,
)
from roomlight.evaluation.bench.rendering import object_coverage, render_view

__all__ = ["BenchConfig", "BENCH_MATERIALS", "MANIFEST", "find_panoramas", "load_emitter_panorama",
           "build_panorama", "make_benchmark", "read_manifest"]

#: The paper's three materials: gray diffuse, silver rough conductor, silver mirror.
BENCH_MATERIALS = ("diffuse", "matte", "mirror")
MANIFEST = "manifest.json"
MANIFEST_VERSION = 1
#: Seeds of the ground-truth renders (the runner renders with other seeds).
GT_SEEDS = {"input": 0, "eval": 1 << 20}


@dataclass(frozen=True)
class BenchConfig(StrictConfig):
    """Settings of ``roomlight bench make``; the defaults are small enough for a CPU.

    The paper: ``emitter_height=512, width=height=1000, spp=4096``.
    """

    n: int = 25                                        #: panoramas used (the first n, sorted by name)
    seed: int = 0                                      #: base seed (each panorama seeds from it and its name)
    emitter_height: int = 128                          #: emitter resolution H (W = 2H)
    width: int = 128                                   #: image width, pixels
    height: int = 128                                  #: image height, pixels
    fov: float = 65.0                                  #: horizontal field of view, degrees
    spp: int = 256                                     #: samples per pixel of the ground-truth renders
    max_depth: int = 4                                 #: longest light path (prb integrator)
    materials: tuple[str, ...] = BENCH_MATERIALS       #: one scene per material
    #: one scene per panorama instead, the k-th panorama (by name) in materials[k mod len]: a
    #: benchmark that spreads its materials over more rooms for the same cost (the demo's)
    material_per_panorama: bool = False
    shapes: tuple[str, ...] = ("knot", "spiky")        #: input-view shapes (2; more: two drawn per panorama)
    key: float = EXPOSURE_KEY                          #: exposure key (log-average luminance of the objects)
    box_range: tuple[float, float] = (0.25, 0.35)      #: screen box side, fraction of the frame width
    strata: tuple[tuple[float, float], ...] = STRATA   #: relative depth strata
    margin: float = 0.05                               #: clearance of objects to the emitter (fraction)
    supersample: int = 4                               #: mask rays per pixel along each axis

    def for_panorama(self, index: int) -> "BenchConfig":
        """The settings the ``index``-th panorama is built with: these, or with its one material."""
        if not self.material_per_panorama:
            return self
        return self.override(materials=(self.materials[index % len(self.materials)],))

    def placement(self) -> PlacementConfig:
        return PlacementConfig(fov=self.fov, width=self.width, height=self.height, box_range=tuple(self.box_range),
                               strata=tuple(tuple(s) for s in self.strata), margin=self.margin)

    def to_dict(self) -> dict:
        return json.loads(json.dumps(asdict(self)))

    def scene_settings(self) -> dict:
        """The settings a panorama's scenes depend on (all but ``n``): a built panorama is reused
        only when they match."""
        d = self.to_dict()
        d.pop("n")
        return d

    def override(self, **changes) -> BenchConfig:
        """A copy with the fields that are not None changed; unknown names and wrong types are refused."""
        return super().override(**{k: v for k, v in changes.items() if v is not None})


def _safe_name(stem: str) -> str:
    return re.sub(r"[^A-Za-z0-9._-]+", "_", stem) or "panorama"


def find_panoramas(source, n: int | None = None) -> list[Path]:
    """The panorama EXRs of a folder (sorted by name, the first ``n``), or a single EXR file."""
    p = Path(source)
    if p.is_file():
        return [p]
    if not p.is_dir():
        raise BenchError(f"--panos {p}: no such folder")
    files = sorted(f for f in p.iterdir() if f.is_file() and f.suffix.lower() == ".exr")
    if not files:
        raise BenchError(f"--panos {p}: holds no .exr panorama (R, G, B + Z depth)")
    return files[:n] if n else files


def load_emitter_panorama(path: Path, height: int) -> tuple[torch.Tensor, torch.Tensor]:
    """Read a panorama with depth and resample it to ``height`` x ``2 height``.

    Returns:
        radiance (H, W, 3) float32 linear, depth (H, W) float32 metres.
    """
    from roomlight.errors import InputFileError
    from roomlight.core.geometry.resample import resize_panorama
    from roomlight.core.io import read_panorama

    try:
        pano = read_panorama(path)
    except InputFileError as exc:  # the reader's repair flags are not options of `bench make`
        raise InputFileError(exc.path, exc.problem, "fix the panorama; a benchmark's ground truth is never "
                             "repaired") from None
    if pano.depth is None:
        raise BenchError(f"{path}: has no depth channel (Z, or A in the authors' layout); the benchmark's "
                         "emitters need radiance + depth panoramas")
    x = torch.cat([torch.from_numpy(pano.radiance).permute(2, 0, 1), torch.from_numpy(pano.depth)[None]])[None]
    x = resize_panorama(x.double(), height)[0].float()
    return x[:3].permute(1, 2, 0).contiguous(), x[3].contiguous()


def _scene_spec(root: Path, placed, material: str, config: BenchConfig, files: dict | None = None, metadata=None):
    from roomlight.fitting.scene.description import (
        CameraSpec,
        EmitterSpec,
        MaterialSpec,
        SceneSpec,
        ViewSpec,
    )

    cam = CameraSpec(fov=config.fov, width=config.width, height=config.height)
    mat = MaterialSpec(material)
    objects = {o.id: o.object_spec(mat) for o in placed}
    files = files or {}
    views = {}
    for view, ids in (("input", [o.id for o in placed if o.role == "input"]),
                      ("eval", [o.id for o in placed if o.role == "probe"])):
        views[view] = ViewSpec(view, cam, ids, image=files.get(f"{view}.exr"), ldr=files.get(f"{view}.png"),
                               mask=files.get(f"{view}_mask.png"))
    emitter = EmitterSpec(files["emitter.exr"]) if "emitter.exr" in files else None
    return SceneSpec(root, objects, views, emitter, metadata or {})


def _write_rgb_exr(path: Path, img: torch.Tensor) -> None:
    from roomlight.core.io import write_exr

    a = img.detach().float().cpu().numpy()
    write_exr(path, {"R": a[..., 0], "G": a[..., 1], "B": a[..., 2]}, half=False)


def build_panorama(path: Path, out_dir: Path, config: BenchConfig, progress=None) -> dict:
    """Build the scenes of one panorama (every material) and return its record.

    Args:
        path: panorama EXR (R, G, B + Z). out_dir: the benchmark root.
        progress: an optional tqdm bar advanced once per material.
    """
    from roomlight.core.io import save_png, write_panorama
    from roomlight.fitting.scene.description import save_scene

    name = _safe_name(path.stem)
    pano_dir = out_dir / name
    radiance, depth = load_emitter_panorama(path, config.emitter_height)  # refused before anything is written
    pano_dir.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng([config.seed, zlib.crc32(name.encode())])
    shapes = list(config.shapes)
    if len(shapes) < 2:
        raise BenchError(f"--shapes: need at least two input-view shapes, got {', '.join(shapes) or 'none'}")
    if len(shapes) > 2:
        shapes = [shapes[i] for i in rng.choice(len(shapes), 2, replace=False)]
    placed = place_objects(EmitterProbe(depth), rng, shapes, config.placement())

    geometry = _scene_spec(pano_dir, placed, "diffuse", config)
    masks = {}
    for view in ("input", "eval"):
        coverage, _ = object_coverage(geometry, view, config.supersample)
        masks[view] = coverage >= 1.0 - 1e-6
        if not masks[view].any():
            raise BenchError(f"{path}: the {view} view's objects cover no whole pixel at "
                             f"{config.width}x{config.height}; use a larger image")

    record = {"name": name, "source": str(path.resolve()), "placement": [o.to_dict() for o in placed],
              "config": config.scene_settings(), "scenes": []}
    for material in config.materials:
        sdir = pano_dir / material
        sdir.mkdir(exist_ok=True)
        spec = _scene_spec(sdir, placed, material, config)
        hdr = {view: render_view(spec, view, radiance, depth, "mesh", config.spp, GT_SEEDS[view], config.max_depth)
               for view in ("input", "eval")}
        k = exposure_for(hdr["input"], masks["input"], config.key)
        files = {"emitter.exr": sdir / "emitter.exr"}
        write_panorama(files["emitter.exr"], ((radiance * k).numpy(), depth.numpy()), half=False,
                       metadata={"exposure": k, "source": str(path.resolve())})
        saturated = {}
        for view in ("input", "eval"):
            img = hdr[view] * k
            ldr = record_ldr(img)
            files[f"{view}.exr"] = sdir / f"{view}.exr"
            files[f"{view}.png"] = sdir / f"{view}.png"
            files[f"{view}_mask.png"] = sdir / f"{view}_mask.png"
            _write_rgb_exr(files[f"{view}.exr"], img)
            save_png(files[f"{view}.png"], ldr)
            save_png(files[f"{view}_mask.png"], (masks[view] * 255).astype(np.uint8))
            saturated[view] = saturated_fraction(ldr, masks[view])
        meta = {"benchmark": {"panorama": name, "source": str(path.resolve()), "material": material,
                              "exposure": k, "key": config.key, "spp": config.spp,
                              "saturated_fraction": saturated, "placement": record["placement"]}}
        spec = _scene_spec(sdir, placed, material, config, files, meta)
        save_scene(spec, sdir / "scene.json")
        record["scenes"].append({"id": f"{name}/{material}", "panorama": name, "material": material,
                                 "scene": f"{name}/{material}/scene.json", "exposure": k,
                                 "saturated_fraction": saturated,
                                 "mask_pixels": {v: int(m.sum()) for v, m in masks.items()}})
        if progress is not None:
            progress.update()
    text = json.dumps(record, indent=2)
    (pano_dir / "panorama.json").write_text(text)
    return json.loads(text)  # plain JSON types, as a resumed build reads it back


def read_record(path: Path, settings: dict) -> dict | None:
    """The JSON record at ``path`` when it exists, parses and was written with these ``settings``
    (its ``config`` entry); None otherwise, so the work it records is done again."""
    if not path.is_file():
        return None
    try:
        rec = json.loads(path.read_text())
    except ValueError:
        return None
    return rec if rec.get("config") == settings else None


def _done_record(pano_dir: Path, config: BenchConfig) -> dict | None:
    rec = read_record(pano_dir / "panorama.json", config.scene_settings())
    if rec is None:
        return None
    if not all((pano_dir.parent / s["scene"]).is_file() for s in rec.get("scenes", [])):
        return None
    return rec


def make_benchmark(panos, out_dir, config: BenchConfig | None = None, overwrite: bool = False,
                   progress: bool = True) -> dict:
    """Build the benchmark (see the module docstring) and return the manifest it writes.

    A panorama already built with the same settings is reused unless ``overwrite``.
    """
    from roomlight.fitting.scene.description import MATERIAL_TYPES
    from roomlight.fitting.scene.shapes import BUILTIN_SHAPES

    config = config or BenchConfig()
    for m in config.materials:
        if m not in MATERIAL_TYPES:
            raise BenchError(f"--materials: unknown material {m!r}; choose from {', '.join(MATERIAL_TYPES)}")
    for s in config.shapes:
        if s not in BUILTIN_SHAPES and not (Path(s).is_file() and Path(s).suffix.lower() in (".ply", ".obj")):
            raise BenchError(f"--shapes: {s!r} is neither a built-in shape ({', '.join(BUILTIN_SHAPES)}) "
                             "nor a .ply/.obj file")
    # Mesh files by absolute path, so that scene files in other folders find them.
    shapes = tuple(s if s in BUILTIN_SHAPES else str(Path(s).resolve()) for s in config.shapes)
    config = config.override(shapes=shapes)
    if config.width <= 0 or config.height <= 0 or config.spp <= 0 or config.emitter_height <= 0:
        raise BenchError("bench make: image size, emitter height and spp must be positive")
    files = find_panoramas(panos, config.n)
    names = [_safe_name(f.stem) for f in files]
    if len(set(names)) != len(names):
        raise BenchError(f"--panos {panos}: two panoramas map to the same scene name; rename them")
    out = Path(out_dir)
    created = not out.exists()
    out.mkdir(parents=True, exist_ok=True)
    bar = None
    if progress:
        from roomlight.core.progress import progress_bar

        per = 1 if config.material_per_panorama else len(config.materials)
        bar = progress_bar(total=len(files) * per, desc="bench make", unit="scene")
    records = []
    try:
        for index, (f, name) in enumerate(zip(files, names, strict=True)):
            pconfig = config.for_panorama(index)
            rec = None if overwrite else _done_record(out / name, pconfig)
            if rec is None:
                if bar is not None:
                    bar.set_postfix_str(name)
                try:
                    rec = build_panorama(f, out, pconfig, bar)
                except BaseException:
                    # Built panoramas stay (a re-run reuses them); the one that failed leaves nothing.
                    if (out / name).is_dir() and _done_record(out / name, pconfig) is None:
                        shutil.rmtree(out / name, ignore_errors=True)
                    if created and not any(out.iterdir()):
                        out.rmdir()
                    raise
            elif bar is not None:
                bar.update(len(pconfig.materials))
            records.append(rec)
    finally:
        if bar is not None:
            bar.close()
    manifest = {"version": MANIFEST_VERSION, "config": config.to_dict(),
                "panoramas": [{k: r[k] for k in ("name", "source", "placement")} for r in records],
                "scenes": [s for r in records for s in r["scenes"]]}
    (out / MANIFEST).write_text(json.dumps(manifest, indent=2))
    return manifest


_MANIFEST_KEYS = ("version", "config", "panoramas", "scenes")
_SCENE_KEYS = {"id": str, "panorama": str, "material": str, "scene": str, "exposure": (int, float),
               "saturated_fraction": dict, "mask_pixels": dict}


def read_manifest(bench_dir) -> dict:
    """The manifest of a benchmark directory (errors name the file and the field's path)."""
    from roomlight.core.config import ConfigError, check_keys

    p = Path(bench_dir)
    f = p / MANIFEST if p.is_dir() else p
    if not f.is_file():
        raise BenchError(f"{f}: no benchmark manifest (build one with `roomlight bench make`)")
    try:
        m = json.loads(f.read_text())
    except (ValueError, UnicodeDecodeError) as exc:
        raise BenchError(f"{f}: not valid JSON: {exc}") from None
    if not isinstance(m, dict) or not isinstance(m.get("scenes"), list):
        raise BenchError(f"{f}: not a benchmark manifest (no 'scenes' list)")
    try:
        check_keys(m, _MANIFEST_KEYS, "manifest")
        if m.get("version", MANIFEST_VERSION) != MANIFEST_VERSION:
            raise ConfigError(f"manifest.version: this roomlight reads version {MANIFEST_VERSION}, "
                              f"got {m.get('version')!r}")
        if "config" in m:
            BenchConfig.from_dict(m["config"], where="manifest.config")
        for i, s in enumerate(m["scenes"]):
            where = f"manifest.scenes[{i}]"
            check_keys(s, _SCENE_KEYS, where)
            for key, kind in _SCENE_KEYS.items():
                if key in ("id", "panorama", "material", "scene") and key not in s:
                    raise ConfigError(f"{where}.{key}: missing (required)")
                if key in s and (not isinstance(s[key], kind) or isinstance(s[key], bool)):
                    raise ConfigError(f"{where}.{key}: expected {getattr(kind, '__name__', 'a number')}, "
                                      f"got {s[key]!r}")
    except ConfigError as exc:
        raise BenchError(f"{f}: {exc}") from None
    return m
