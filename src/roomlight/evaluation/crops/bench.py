"""The crop benchmark: the field's three-sphere protocol as a roomlight benchmark kind.

- **make** (:func:`make_crop_set`): each panorama (a roomlight panorama EXR, or any equirectangular
  linear EXR, e.g. the CC0 HDRIs Blender ships) becomes ``SET/<name>/``: ``crop.png`` (the protocol's
  input, :func:`~roomlight.evaluation.crops.protocol.make_crop`), ``truth.exr`` (the panorama at 128 x 256,
  linear) and ``crop.json`` (where it came from, the crop's camera).
- **run** (:func:`run_crop_benchmark`): every (crop, method) case through the one harness runner
  (resumable, sharded, failures recorded): the method's panorama (``pred.exr``), the three spheres
  under it and under the truth (``spheres.png``), and ``result.json`` with the four scores per sphere.
- **report** (:func:`crop_report`): the means per method and sphere, the paired differences of
  ``estimate`` against the others, and the published numbers of the field beside them.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from roomlight.core.render.variant import thread_record
from roomlight.errors import RoomlightError
from roomlight.evaluation.harness.records import RESULT, write_json
from roomlight.evaluation.harness.runner import Case, run_cases

__all__ = ["make_crop_set", "crop_cases", "run_crop_case", "run_crop_benchmark", "collect_crop_results",
           "crop_report", "PUBLISHED", "METRICS"]

METRICS = ("si_rmse", "angular_error", "rmse", "norm_rmse")
#: The field's published scores on its own test sets, as (si-RMSE, angular error in degrees) per sphere
#: (diffuse, matte, mirror). Not comparable number for number: other panoramas, other renderers.
PUBLISHED = {
    "Laval Indoor (289 panoramas)": {
        "StyleLight (re-run with its code)": ((0.13, 0.31, 0.55), (4.24, 4.74, 6.78)),
        "DiffusionLight": ((0.14, 0.33, 0.60), (2.14, 3.42, 5.94)),
        "LuxDiT": ((0.112, 0.297, 0.586), (2.56, 3.53, 5.64)),
    },
    "Poly Haven (181 held-out panoramas)": {
        "DiffusionLight": ((0.113, 0.270, 0.519), (2.20, 3.12, 4.10)),
        "LuxDiT": ((0.077, 0.196, 0.442), (1.24, 1.98, 2.78)),
    },
}


def _read_panorama_any(path: Path) -> np.ndarray:
    """(H, W, 3) linear radiance of a panorama EXR (roomlight's, or any R, G, B equirectangular EXR)."""
    from roomlight.core.io import read_exr

    ch = read_exr(path)
    if not all(c in ch for c in "RGB"):
        raise RoomlightError(f"{path}: expected R, G, B channels, found {', '.join(sorted(ch))}")
    img = np.stack([ch[c] for c in "RGB"], -1).astype(np.float32)
    if img.shape[1] != 2 * img.shape[0]:
        raise RoomlightError(f"{path}: {img.shape[1]}x{img.shape[0]} is not an equirectangular panorama (W = 2H)")
    if not np.isfinite(img).all():
        raise RoomlightError(f"{path}: non-finite values")
    return np.maximum(img, 0.0)


def make_crop_set(panoramas, out_dir, source: str = "", progress: bool = True) -> list[str]:
    """Write the crops of ``panoramas`` (paths) into ``out_dir``; returns the names made (module docstring)."""
    from roomlight.core.io import save_png, write_exr
    from roomlight.core.progress import progress_bar
    from roomlight.evaluation.crops.protocol import (CROP_FORWARD, CROP_SIZE, CROP_VFOV, crop_camera_fov_x,
                                                     make_crop, resize_panorama, SCORE_SIZE)

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    names = []
    paths = [Path(p) for p in panoramas]
    for p in progress_bar(paths, desc="make-crops", unit="panorama", disable=not progress):
        name = p.stem if not p.stem.startswith("room") else p.stem
        d = out / name
        if (d / "crop.json").is_file():
            names.append(name)
            continue
        pano = _read_panorama_any(p)
        d.mkdir(parents=True, exist_ok=True)
        crop = make_crop(pano)
        save_png(d / "crop.png", np.rint(crop * 255).astype(np.uint8))
        truth = resize_panorama(pano, SCORE_SIZE)
        write_exr(d / "truth.exr", {c: truth[..., k] for k, c in enumerate("RGB")}, half=False)
        write_json(d / "crop.json", {"source": str(p.resolve()), "set": source, "size": [CROP_SIZE[1], CROP_SIZE[0]],
                                     "vfov_deg": CROP_VFOV, "hfov_deg": crop_camera_fov_x(),
                                     "forward": list(CROP_FORWARD), "panorama_size": list(pano.shape[:2])})
        names.append(name)
    (out / "crops.json").write_text(json.dumps({"crops": sorted(set(names) | set(_listed(out)))}, indent=2))
    return names


def _listed(out: Path) -> list[str]:
    f = out / "crops.json"
    return json.loads(f.read_text())["crops"] if f.is_file() else []


def crop_cases(set_dir, methods) -> list[Case]:
    d = Path(set_dir)
    names = sorted(p.parent.name for p in d.glob("*/crop.json"))
    if not names:
        raise RoomlightError(f"{d}: no crops (make them with `roomlight bench make-crops`)")
    return [Case(n, m, d / n) for n in names for m in methods]


def _read_crop(d: Path) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(d / "crop.png").convert("RGB"), dtype=np.float32) / 255.0


def _read_truth(d: Path) -> np.ndarray:
    from roomlight.core.io import read_exr

    ch = read_exr(d / "truth.exr")
    return np.stack([ch[c] for c in "RGB"], -1).astype(np.float32)


def _truth_spheres(case: Case, out_dir, spp: int) -> dict[str, np.ndarray]:
    """The spheres under the crop's true panorama, rendered once per crop (at twice ``spp``, so their
    noise adds less to every method's score) and kept in ``RES/truth/<crop>.npz``."""
    from roomlight.evaluation.crops.protocol import render_spheres, score_panorama

    f = Path(out_dir) / "truth" / f"{case.item}.npz"
    if f.is_file():
        with np.load(f) as z:
            return {k: z[k] for k in z.files}
    true = render_spheres(score_panorama(_read_truth(case.source)), spp=2 * spp, seed=1)
    f.parent.mkdir(parents=True, exist_ok=True)
    tmp = f.with_suffix(".tmp.npz")
    np.savez(tmp, **true)
    tmp.replace(f)
    return true


def run_crop_case(case: Case, out_dir, model=None, spp: int = 256) -> dict:
    """Predict, render the spheres, score; write the case folder (``result.json`` last)."""
    import time

    from roomlight.core.io import save_png, write_exr
    from roomlight.core.io.preview import tonemap_gamma
    from roomlight.evaluation.crops.metrics import sphere_scores
    from roomlight.evaluation.crops.predict import predict
    from roomlight.evaluation.crops.protocol import render_spheres, score_panorama, sphere_mask

    t0 = time.perf_counter()
    cdir = case.directory(out_dir)
    cdir.mkdir(parents=True, exist_ok=True)
    pred = predict(case.method, _read_crop(case.source), model)
    seconds = time.perf_counter() - t0
    write_exr(cdir / "pred.exr", {c: pred[..., k] for k, c in enumerate("RGB")}, half=False)
    mine = render_spheres(score_panorama(pred), spp=spp)
    true = _truth_spheres(case, out_dir, spp)
    mask = sphere_mask(mine["diffuse"].shape[0])
    scores = {m: sphere_scores(mine[m], true[m], mask) for m in mine}
    rows = [np.concatenate([mine[m], true[m]], 1) for m in mine]
    save_png(cdir / "spheres.png", tonemap_gamma(np.concatenate(rows, 0)))
    record = {"crop": case.item, "method": case.method, "scores": scores, "predict_seconds": round(seconds, 4),
              "spp": spp, "sphere_pixels": int(mask.sum()), "threads": thread_record()}
    write_json(cdir / RESULT, record)
    return record


def run_crop_benchmark(set_dir, out_dir, methods, model=None, spp: int = 256, shard=(0, 1), progress: bool = True):
    from functools import partial

    from roomlight.evaluation.harness.records import check_run_file
    from roomlight.evaluation.harness.runner import shard_cases

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    settings = {"set": str(Path(set_dir).resolve()), "kind": "crops", "methods": list(methods), "spp": spp}
    check_run_file(out, settings, ("spp",))
    cases = shard_cases(crop_cases(set_dir, methods), shard)
    return run_cases(cases, out, partial(run_crop_case, out_dir=out, model=model, spp=spp), desc="run-crops",
                     progress=progress)


def collect_crop_results(res_dir) -> list[dict]:
    from roomlight.evaluation.harness.records import read_case_records

    return read_case_records(res_dir, ("crop", "method", "scores"), "roomlight bench run-crops")


def crop_report(res_dir, reference: str = "estimate") -> str:
    """The report's Markdown (module docstring)."""
    from roomlight.core.stats import bootstrap_mean_interval
    from roomlight.evaluation.crops.protocol import SPHERE_MATERIALS
    from roomlight.fitting.methods import method_order

    recs = collect_crop_results(res_dir)
    if not recs:
        raise RoomlightError(f"{res_dir}: no finished case")
    order = [m for m in method_order() if any(r["method"] == m for r in recs)]
    n_crops = len({r["crop"] for r in recs})
    md = [f"# Crop benchmark: {n_crops} crops", "",
          "The field's three-sphere protocol (docs/benchmark.md): mean over crops, lower is better.", "",
          "| Method | " + " | ".join(f"si-RMSE {m}" for m in SPHERE_MATERIALS) + " | "
          + " | ".join(f"angular error (°) {m}" for m in SPHERE_MATERIALS) + " | "
          + " | ".join(f"RMSE {m}" for m in SPHERE_MATERIALS) + " | n |",
          "|---|" + ":---:|" * 9 + "---:|"]
    by = {}
    for r in recs:
        by.setdefault(r["method"], {})[r["crop"]] = r["scores"]
    for m in order:
        cells = []
        for metric in ("si_rmse", "angular_error", "rmse"):
            for s in SPHERE_MATERIALS:
                v = [sc[s][metric] for sc in by[m].values()]
                cells.append(f"{np.mean(v):.3f}" if metric != "angular_error" else f"{np.mean(v):.2f}")
        md.append(f"| {m} | " + " | ".join(cells) + f" | {len(by[m])} |")
    if reference in by:
        md += ["", f"Paired per crop, {reference} − other (negative: {reference} better), mean [95 % interval]:", "",
               "| other | " + " | ".join(f"si-RMSE {s}" for s in SPHERE_MATERIALS) + " | "
               + " | ".join(f"angular error {s}" for s in SPHERE_MATERIALS) + " |", "|---|" + ":---:|" * 6]
        for m in order:
            if m == reference:
                continue
            common = sorted(set(by[m]) & set(by[reference]))
            cells = []
            for metric in ("si_rmse", "angular_error"):
                for s in SPHERE_MATERIALS:
                    d = np.array([by[reference][c][s][metric] - by[m][c][s][metric] for c in common])
                    lo, hi = bootstrap_mean_interval(d)
                    mark = " ✓" if hi < 0 else (" ✗" if lo > 0 else "")
                    cells.append(f"{d.mean():+.3f} [{lo:+.3f}, {hi:+.3f}]{mark}")
            md.append(f"| {m} | " + " | ".join(cells) + " |")
    md += ["", "Published, on other test sets (not comparable number for number):", "",
           "| set | method | si-RMSE diffuse / matte / mirror | angular error (°) diffuse / matte / mirror |",
           "|---|---|:---:|:---:|"]
    for dataset, rows in PUBLISHED.items():
        for name, (si, ang) in rows.items():
            md.append(f"| {dataset} | {name} | {' / '.join(f'{v:g}' for v in si)} | {' / '.join(f'{v:g}' for v in ang)} |")
    return "\n".join(md) + "\n"
