"""Dataset statistics: the prior's normalisation (docs/model.md) and a summary of the data.

The normalisation statistics are the per-channel mean and standard deviation of
(log1p R, log1p G, log1p B, log D) over every pixel of the training panoramas, computed at the
training resolution after exposure calibration, exactly as the network will see them
(:meth:`roomlight.prior.model.Normalization.from_data`). They are stored in every checkpoint.
"""

from __future__ import annotations

import math

import numpy as np
import torch

from roomlight.core.color import luminance_torch
from roomlight.errors import RoomlightError
from roomlight.prior.model.normalization import Normalization

__all__ = ["dataset_statistics", "normalization_from_dataset", "NoUsablePanorama"]


class NoUsablePanorama(RoomlightError):
    """Every file of a dataset was skipped; ``skipped`` lists (name, reason) for each."""

    def __init__(self, where, skipped: list):
        self.skipped = list(skipped)
        super().__init__(f"no usable panorama in {where}" + (f" ({len(skipped)} skipped: "
                         f"{'; '.join(f'{n}: {why}' for n, why in skipped[:3])}"
                         f"{'; ...' if len(skipped) > 3 else ''})" if skipped else ""))


def _good_items(dataset, skipped: list, progress: bool, desc: str):
    from roomlight.core.progress import progress_bar

    for i in progress_bar(range(len(dataset)), desc=desc, unit="pano", disable=not progress):
        item = dataset[i]
        if "error" in item:
            skipped.append((item["name"], item["error"]))
            continue
        yield item


def normalization_from_dataset(dataset, progress: bool = False) -> tuple[Normalization, list]:
    """Normalisation statistics of a :class:`~roomlight.prior.data.PanoramaDataset`.

    Returns:
        (Normalization, skipped) where skipped lists (name, reason) of unusable files.
    """
    skipped: list = []
    pairs = ((it["radiance"], it["depth"]) for it in _good_items(dataset, skipped, progress, "statistics"))
    try:
        return Normalization.from_data(pairs), skipped
    except RoomlightError:
        if skipped or len(dataset) == 0:
            raise NoUsablePanorama(_folder(dataset), skipped) from None
        raise


def _folder(dataset):
    root = getattr(dataset, "root", None)
    files = getattr(dataset, "files", [])
    return root if root is not None else (files[0].parent if files else "the dataset")


def dataset_statistics(dataset, progress: bool = True, sample_pixels: int = 4096) -> dict:
    """Normalisation statistics plus a summary of the data (JSON-serialisable).

    Returns a dict with ``count``, ``resolution``, ``normalization`` (channels, mean, std),
    ``luminance`` percentiles (of calibrated radiance; p50/p90/p99/p99.9/max), ``dynamic_range``
    (median over panoramas of max/p1 luminance, in stops), ``depth`` (min, p1, median, p99, max,
    in the dataset's depth units) and ``skipped`` (name, reason) pairs. Percentiles use a fixed
    random subset of ``sample_pixels`` pixels per panorama (plus each panorama's maximum).
    """
    skipped: list = []
    lum_samples, depth_samples, stops, maxima = [], [], [], []
    dmin, dmax = math.inf, 0.0
    g = torch.Generator().manual_seed(0)
    used = [0]  # panoramas that entered the statistics

    def gen():
        nonlocal dmin, dmax
        for it in _good_items(dataset, skipped, progress, "statistics"):
            rad, dep = it["radiance"], it["depth"]
            y = luminance_torch(rad).flatten()
            d = dep.flatten()
            idx = torch.randint(0, y.numel(), (min(sample_pixels, y.numel()),), generator=g)
            lum_samples.append(y[idx])
            depth_samples.append(d[idx])
            maxima.append(float(y.max()))
            p1 = float(torch.quantile(y, 0.01))
            stops.append(math.log2(max(float(y.max()), 1e-12) / max(p1, 1e-6)))
            dmin, dmax = min(dmin, float(d.min())), max(dmax, float(d.max()))
            used[0] += 1
            yield rad, dep

    try:
        norm = Normalization.from_data(gen())
    except RoomlightError:  # no usable panorama at all
        norm = None
    out: dict = {"count": used[0], "resolution": list(dataset.resolution)}
    out["normalization"] = norm.to_dict() if norm is not None else None
    if lum_samples:
        lum = torch.cat(lum_samples + [torch.tensor(maxima)]).double().numpy()
        dep = torch.cat(depth_samples).double().numpy()
        q = lambda a, p: float(np.percentile(a, p))  # noqa: E731
        out["luminance"] = {"p50": q(lum, 50), "p90": q(lum, 90), "p99": q(lum, 99), "p99.9": q(lum, 99.9),
                            "max": float(max(maxima))}
        out["dynamic_range_stops"] = {"median": float(np.median(stops)), "max": float(max(stops))}
        out["depth"] = {"min": dmin, "p1": q(dep, 1), "median": q(dep, 50), "p99": q(dep, 99), "max": dmax}
    out["skipped"] = [{"name": n, "reason": r} for n, r in skipped]
    return out
