"""One room's record in the capacity experiment: the emitters compared, the viewpoints, the scores.

Shared by the run (:mod:`roomlight.evaluation.experiments.capacity`), its report and its figures.
"""

from __future__ import annotations

import numpy as np

__all__ = ["KINDS", "KIND_LABELS", "VIEW_TAGS", "RESULT", "PAPER_RATIO", "MATERIAL_LABELS", "score_renders",
           "room_cells"]

#: The emitters compared, in table order.
KINDS = ("mesh", "envmap", "sphere")
KIND_LABELS = {"mesh": "2.5D area light", "envmap": "Environment map", "sphere": "Sphere proxy"}
#: Capture points: centre of probe A, centre of probe B, their midpoint.
VIEW_TAGS = ("A", "B", "M")
#: Written last into a room's folder: the room is done.
RESULT = "result.json"
#: The paper's statement: the 2.5D light's RMSE is 2x to 5x below the environment map's.
PAPER_RATIO = (2.0, 5.0)
MATERIAL_LABELS = {"diffuse": "Diffuse", "matte": "Matte silver", "mirror": "Mirror", "glossy": "Glossy",
                   "white": "White"}


def _rmse(a: np.ndarray, b: np.ndarray, mask: np.ndarray) -> float:
    from roomlight.evaluation.harness.metrics import rmse_hdr

    return rmse_hdr(a, b, mask)


def score_renders(gt, emit, emit2, masks, materials) -> dict:
    """``{"rmse": {material: {...}}}``: linear RMSE over each probe's mask.

    Args:
        gt: (M, 2, P, h, w, 3) two ground-truth renders per material and probe.
        emit: (M, len(KINDS), V, P, h, w, 3) renders under each emitter at each viewpoint.
        emit2: (M, P, h, w, 3) the 2.5D light at the midpoint again, another seed.
        masks: (P, h, w) bool probe pixels.
        materials: the M material names.
    Returns:
        per material: ``noise_floor`` and ``mesh_noise`` (per probe), and for each kind a
        (V, P) list of RMSEs against the first ground-truth render.
    """
    rmse: dict = {}
    P = masks.shape[0]
    for mi_idx, material in enumerate(materials):
        ref = gt[mi_idx, 0]
        r = {"noise_floor": [_rmse(gt[mi_idx, 1, k], ref[k], masks[k]) for k in range(P)],
             "mesh_noise": [_rmse(emit2[mi_idx, k], emit[mi_idx, 0, 2, k], masks[k]) for k in range(P)]}
        for ki, kind in enumerate(KINDS):
            r[kind] = [[_rmse(emit[mi_idx, ki, vi, k], ref[k], masks[k]) for k in range(P)]
                       for vi in range(emit.shape[2])]
        rmse[material] = r
    return {"rmse": rmse}


def room_cells(record: dict) -> dict:
    """``{material: {"noise_floor": x, "mesh_noise": x, kind: [min, max], kind + "_mean": x}}`` of one room."""
    out = {}
    for material, r in record["rmse"].items():
        cell = {"noise_floor": float(np.mean(r["noise_floor"])), "mesh_noise": float(np.mean(r["mesh_noise"]))}
        for kind in KINDS:
            per_view = np.asarray(r[kind], np.float64).mean(axis=1)  # average over probes
            cell[kind] = [float(per_view.min()), float(per_view.max())]
            cell[kind + "_mean"] = float(per_view.mean())
        out[material] = cell
    return out
