"""Running an analysis-only case (the C-beam): the load-factor sweep, summary.json and the
deformed-mesh picture."""
from __future__ import annotations

import json
import time

import numpy as np

from . import resources
from .errors import InputError
from .files import atomic_path, atomic_write_text, claim_folder
from .runner import prepare_output
from .studies import c_beam_limit


def deformed_png(path, mesh, gfu, title: str):
    """Undeformed mesh (grey) under the deformed mesh (true scale), solid and void coloured."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection

    pts = np.array([v.point for v in mesh.vertices])
    disp = np.array([gfu(mesh(*p)) for p in pts])
    els = [[v.nr for v in el.vertices] for el in mesh.Elements()]
    void = np.array([el.mat == "void" for el in mesh.Elements()])
    fig, ax = plt.subplots(figsize=(6, 6))
    ax.add_collection(PolyCollection([pts[e] for e in els], facecolors="none",
                                     edgecolors="0.75", linewidths=0.5))
    moved = pts + disp
    colors = np.where(void, "#9ecae1", "#08306b")
    ax.add_collection(PolyCollection([moved[e] for e in els], facecolors=colors,
                                     edgecolors="k", linewidths=0.4, alpha=0.8))
    allp = np.vstack([pts, moved])
    ax.set_xlim(allp[:, 0].min() - 0.5, allp[:, 0].max() + 0.5)
    ax.set_ylim(allp[:, 1].min() - 0.5, allp[:, 1].max() + 0.5)
    ax.set_aspect("equal")
    ax.set_title(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def run_analysis_case(case, params, out, *, quiet: bool = False, overwrite: bool = False) -> int:
    """The C-beam's load-factor sweep: summary.json and deformed.png in ``out`` (a folder
    holding earlier results is refused unless ``overwrite``)."""
    if case.name != "c-beam":
        raise InputError(f"case '{case.name}' has no analysis driver")
    if params.model not in ("linear", "gnl", "neohookean", "wang"):
        raise InputError(f"model: '{params.model}' cannot be used for the C-beam analysis")
    params = case.resolve(params)
    _check_resources(case, params)  # before the folder is made and the mesh is started
    path = prepare_output(out)
    with claim_folder(path, "run", overwrite=overwrite):
        return _c_beam(case, params, path, quiet)


def _mesh_of(params) -> tuple[str, float]:
    """The C-beam's mesh: ``("quad", 10 / nelx)`` (an nelx x nelx grid on the 10 m square) or
    ``("trig", maxh)`` (Netgen triangles)."""
    return ("quad", 10.0 / params.nelx) if params.nelx > 0 else ("trig", params.maxh)


def _check_resources(case, params) -> None:
    """The C-beam's mesh and analysis checked as a run's (:mod:`pacto_ng.resources`: memory
    and meshing time), one line and no mesh started when they do not fit."""
    kind, h = _mesh_of(params)
    solver = "sparsecholesky"  # a symmetric tangent (no follower load)
    if kind == "quad":
        n = params.nelx
        est = resources.estimate_grid((n, n), params.order, solver=solver)
        what, advice = f"nelx = {n} ({n} x {n} quads)", "give a smaller nelx or order"
    else:
        layout = case.make_geometry(params)
        est = resources.estimate_netgen(
            resources.netgen_elements(layout.width * layout.height, h, 2), params.order, 2,
            solver=solver)
        what, advice = f"maxh = {h:g}", "give a larger maxh or a lower order"
    resources.check(est, what, mesh_time_limit=params.mesh_time_limit, advice=advice)


def _c_beam(case, params, path, quiet: bool) -> int:
    t0 = time.perf_counter()
    mesh_kind, h = _mesh_of(params)
    # the case's own loads: f1 downward at the top arm's end, f2 rightward at the bottom's
    forces = {ld.region: ld.force for ld in case.make_setup(params).loads}
    res = c_beam_limit(params.model, order=params.order, mesh=mesh_kind, h=h,
                       f1=-float(forces["f1"][1]), f2=float(forces["f2"][0]),
                       lam_max=params.load, E1=params.E1, E0_ratio=params.E0 / params.E1,
                       nu=params.nu, thickness=params.thickness, wang_beta=params.wang_beta,
                       wang_eta=params.wang_eta)
    wall = time.perf_counter() - t0
    summ = {
        "case": case.name, "model": params.model, "parameters": params.to_dict(),
        "load_factor_reached": res.load_factor, "forces_reached_N": list(res.forces),
        "reached_requested_maximum": res.reached_max, "stopped_because": res.reason,
        "newton_iterations_total": res.iterations,
        "tip_displacements": {"f1": list(res.tip_displacement[:2]), "f2": list(res.tip_displacement[2:])},
        "load_steps": [list(h_) for h_ in res.history],
        "min_detF_solid_void_per_step": [list(s) for s in res.steps],
        "mesh": {"kind": mesh_kind, "h": h, "elements": res.mechanics.mesh.ne, "order": params.order},
        "wall_time_s": wall,
        "thesis_forces_N": {"neohookean": [0.0009, 0.0099], "wang": [0.0055, 0.0145]},
    }
    with atomic_path(path / "deformed.png") as tmp:
        deformed_png(tmp, res.mechanics.mesh, res.mechanics.u,
                     f"C-beam, {params.model}: λ = {res.load_factor:.3g}, "
                     f"(f1, f2) = ({res.forces[0]:.2g}, {res.forces[1]:.2g}) N")
    atomic_write_text(path / "summary.json", json.dumps(summ, indent=1))  # last: complete
    if not quiet:
        print(f"c-beam {params.model}: largest load factor {res.load_factor:.4g} -> (f1, f2) = "
              f"({res.forces[0]:.4g}, {res.forces[1]:.4g}) N; stopped: {res.reason}; output in {path}")
    return 0
