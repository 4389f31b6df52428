"""Figures of the capacity experiment (PNG, matplotlib's Agg backend).

- ``probes-<material>.png``: the first room's probes (columns) under the 2.5D light and the
  environment map built at each capture point (rows), below their ground truth, with a top view
  of the room: probes, capture points and cameras (the paper's representation figure).
- ``motivation.png``: the two objects at whose centres panoramas were captured, probes A and B
  (silver matte), relit by the 2.5D light and by the environment map of each capture point (rows)
  next to the ground truth (the paper's motivation figure), from the first room.
- ``ratios.png``: per room, environment map / 2.5D light and sphere proxy / 2.5D light (log
  scale) against the paper's 2--5x band.

All images of one figure share one exposure: the ground truth's log-average luminance over the
probe pixels is mapped to 0.18, then clip and gamma 2.2 (the benchmark's LDR mapping).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from roomlight.core.color import MIDDLE_GREY, log_average_np, to_display
from roomlight.evaluation.experiments.capacity_record import KINDS, MATERIAL_LABELS, PAPER_RATIO, VIEW_TAGS

__all__ = ["write_capacity_figures"]


def _exposure(img: np.ndarray, mask: np.ndarray | None = None) -> float:
    la = log_average_np(img, mask)
    return MIDDLE_GREY / la if la > 0 else 1.0


def _save(fig, path: Path) -> Path:
    tmp = path.with_name(f".{path.stem}.tmp.png")
    fig.savefig(tmp, dpi=110, bbox_inches="tight")
    tmp.replace(path)
    return path


def _top_view(ax, record: dict) -> None:
    from matplotlib.patches import Rectangle

    plan = record.get("plan") or {}
    for x0, z0, x1, z1 in plan.get("cells", []):
        ax.add_patch(Rectangle((x0, z0), x1 - x0, z1 - z0, fill=False, lw=1.2, color="0.3"))
    for x0, z0, x1, z1, _kind, light in plan.get("furniture", []):
        if light:  # drawn at least 8 cm wide, so a wall light shows
            cx, cz = 0.5 * (x0 + x1), 0.5 * (z0 + z1)
            hx, hz = max(0.5 * (x1 - x0), 0.04), max(0.5 * (z1 - z0), 0.04)
            ax.add_patch(Rectangle((cx - hx, cz - hz), 2 * hx, 2 * hz, color="gold", alpha=0.9, lw=0))
        else:
            ax.add_patch(Rectangle((x0, z0), x1 - x0, z1 - z0, color="0.8", alpha=0.6, lw=0))
    for i, (x0, z0, x1, z1) in enumerate(plan.get("windows", [])):
        ax.plot([x0, x1], [z0, z1], "-", color="deepskyblue", lw=4, solid_capstyle="butt",
                label="windows" if i == 0 else None)
    lay = record["layout"]
    probes = np.asarray(lay["probes"])
    views = np.asarray(lay["viewpoints"])
    for k, p in enumerate(probes):
        ax.add_patch(plt_circle(p[0], p[2], lay["radius"]))
        ax.annotate("ABC"[k], (p[0], p[2]), textcoords="offset points", xytext=(6, 6), fontsize=8)
    ax.plot(views[:, 0], views[:, 2], "x", color="crimson", ms=7, mew=2, label="capture points")
    for o, t in lay["cameras"]:
        ax.plot([o[0], t[0]], [o[2], t[2]], "-", color="steelblue", lw=0.8)
        ax.plot([o[0]], [o[2]], "o", color="steelblue", ms=3)
    ax.set_aspect("equal")
    ax.invert_yaxis()
    ax.set_xlabel("x (m)")
    ax.set_ylabel("z (m)")
    ax.set_title("top view (gold: lights on)", fontsize=9)
    ax.legend(fontsize=7, loc="best")
    ax.autoscale_view()


def plt_circle(x, z, r):
    from matplotlib.patches import Circle

    return Circle((x, z), r, color="0.2")


def _probe_figure(record: dict, renders, material: str, path: Path) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    m = record["settings"]["materials"].index(material)
    gt, emit, masks = renders["gt"][m, 0], renders["emit"][m], renders["masks"]
    P, V = gt.shape[0], emit.shape[1]
    k_mesh, k_env = KINDS.index("mesh"), KINDS.index("envmap")
    expo = _exposure(np.concatenate([gt[k][masks[k]] for k in range(P)])[None])
    rm = record["rmse"][material]
    fig = plt.figure(figsize=(2.0 * 2 * P + 4.0, 2.1 * (V + 1)))
    grid = fig.add_gridspec(V + 1, 2 * P + 2)
    for k in range(P):
        ax = fig.add_subplot(grid[0, 2 * k:2 * k + 2])
        ax.imshow(to_display(gt[k] * expo))
        ax.set_title(f"probe {'ABC'[k]}: ground truth", fontsize=9)
        ax.axis("off")
        for v in range(V):
            for j, (ki, name) in enumerate(((k_mesh, "2.5D"), (k_env, "env map"))):
                ax = fig.add_subplot(grid[v + 1, 2 * k + j])
                ax.imshow(to_display(emit[ki, v, k] * expo))
                ax.set_title(f"{name} {rm[KINDS[ki]][v][k]:.3f}", fontsize=8)
                ax.set_xticks([])
                ax.set_yticks([])
                if k == 0 and j == 0:
                    ax.set_ylabel(f"captured at {VIEW_TAGS[v]}", fontsize=9)
    _top_view(fig.add_subplot(grid[:, 2 * P:]), record)
    fig.suptitle(f"{record['name']}, {material} probes: renders under emitters captured at A, B and their "
                 f"midpoint M (RMSE to the ground truth)", fontsize=10)
    path = _save(fig, path)
    plt.close(fig)
    return path


def _motivation_figure(record: dict, renders, material: str, path: Path) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    m = record["settings"]["materials"].index(material)
    gt, emit, masks = renders["gt"][m, 0], renders["emit"][m], renders["masks"]
    expo = _exposure(np.concatenate([gt[k][masks[k]] for k in (0, 1)])[None])
    rm = record["rmse"][material]
    columns = [("ground truth (path traced)", None), ("2.5D area light", "mesh"), ("environment map", "envmap")]
    names = {"A": "captured at the centre of A", "B": "captured at the centre of B", "M": "captured at the midpoint"}
    fig, axes = plt.subplots(len(VIEW_TAGS), 3, figsize=(3 * 3.3, len(VIEW_TAGS) * 1.9))
    for r, tag in enumerate(VIEW_TAGS):
        for c, (title, kind) in enumerate(columns):
            ax = axes[r, c]
            pair = [gt[k] if kind is None else emit[KINDS.index(kind), r, k] for k in (0, 1)]
            ax.imshow(to_display(np.concatenate(pair, axis=1) * expo))
            ax.set_xticks([])
            ax.set_yticks([])
            if kind is not None:
                ax.set_xlabel(f"RMSE A {rm[kind][r][0]:.3f}, B {rm[kind][r][1]:.3f}", fontsize=7)
            if r == 0:
                ax.set_title(title, fontsize=9)
            if c == 0:
                ax.set_ylabel(names[tag], fontsize=8)
    fig.suptitle(f"{record['name']}: probes A (left) and B (right), {material}, relit from each capture point",
                 fontsize=10)
    fig.tight_layout()
    path = _save(fig, path)
    plt.close(fig)
    return path


def _ratio_figure(summary: dict, path: Path) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt


    mats = summary["materials"]
    fig, ax = plt.subplots(figsize=(2.2 * len(mats) + 2, 3.4))
    ax.axhspan(*PAPER_RATIO, color="0.9", label="paper: 2–5×")
    ax.axhline(1.0, color="0.5", lw=0.8)
    for i, m in enumerate(mats):
        for key, colour, dx, label in (("envmap_over_mesh", "crimson", -0.12, "env map / 2.5D"),
                                       ("sphere_over_mesh", "steelblue", 0.12, "sphere proxy / 2.5D")):
            s = summary["ratios"][m][key]
            r = np.asarray(s["per_room"])
            ax.plot(np.full(r.size, i + dx), r, "o", color=colour, alpha=0.5, ms=4, label=label if i == 0 else None)
            lo, hi = s["ci95"]
            ax.errorbar([i + dx], [s["geomean"]], yerr=[[s["geomean"] - lo], [hi - s["geomean"]]], fmt="_",
                        color="k", ms=14, capsize=3)
    ax.set_yscale("log")
    ax.set_xticks(range(len(mats)))
    ax.set_xticklabels([MATERIAL_LABELS.get(m, m) for m in mats])
    ax.set_ylabel("RMSE ratio (per room)")
    ax.set_title("Error of each emitter relative to the 2.5D light (bars: geometric mean, 95 % interval)",
                 fontsize=9)
    ax.legend(fontsize=8, loc="best")
    path = _save(fig, path)
    plt.close(fig)
    return path


def write_capacity_figures(out, records: list[dict], summary: dict) -> list[Path]:
    """Write the figures of a run into ``out/figures``; returns their paths."""
    out = Path(out)
    fig_dir = out / "figures"
    fig_dir.mkdir(parents=True, exist_ok=True)
    paths = []
    first = records[0]
    with np.load(out / "rooms" / first["name"] / "renders.npz") as z:
        renders = {k: z[k] for k in z.files}
    materials = first["settings"]["materials"]
    for material in materials:
        paths.append(_probe_figure(first, renders, material, fig_dir / f"probes-{material}.png"))
    shown = "matte" if "matte" in materials else materials[0]
    paths.append(_motivation_figure(first, renders, shown, fig_dir / "motivation.png"))
    paths.append(_ratio_figure(summary, fig_dir / "ratios.png"))
    return paths
