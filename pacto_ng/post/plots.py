"""Pictures of a run: the physical density (design.png) and the convergence history."""
from __future__ import annotations

import numpy as np


def element_polygons(mesh) -> list[np.ndarray]:
    pts = np.array([v.point for v in mesh.vertices])
    return [pts[[v.nr for v in el.vertices]] for el in mesh.Elements()]


def density_png(path, problem, field_name: str | None = None, title: str | None = None):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection

    from ..run import rho_bar_of

    rho = rho_bar_of(problem) if field_name is None else np.asarray(problem.values[field_name])
    polys = element_polygons(problem.mesh)
    allpts = np.concatenate(polys)
    w = np.ptp(allpts[:, 0])
    h = np.ptp(allpts[:, 1])
    fig, ax = plt.subplots(figsize=(8, max(2.0, 8 * h / w)))
    pc = PolyCollection(polys, array=rho, cmap="gray_r", edgecolors="face", linewidths=0.1)
    pc.set_clim(0, 1)
    ax.add_collection(pc)
    ax.set_xlim(allpts[:, 0].min(), allpts[:, 0].max())
    ax.set_ylim(allpts[:, 1].min(), allpts[:, 1].max())
    ax.set_aspect("equal")
    ax.set_title(title or f"{problem.case.name} — {problem.params.model}, ρ̄ "
                 f"(volume {problem.volume_fraction():.3f})")
    fig.colorbar(pc, ax=ax, fraction=0.03)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def convergence_png(path, history: list, objective_name: str):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    it = [h["iteration"] for h in history]
    fig, ax = plt.subplots(figsize=(7, 4))
    ax.plot(it, [h["objective"] for h in history], "b-", label=objective_name)
    ax.set_xlabel("iteration")
    ax.set_ylabel(objective_name, color="b")
    ax2 = ax.twinx()
    ax2.plot(it, [h["volume"] for h in history], "r--", label="volume fraction")
    ax2.set_ylabel("volume fraction", color="r")
    ax.set_title("convergence")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
