"""The results of a run on a distributed mesh (:mod:`pacto_ng.parallel`), written by rank 0.

Every rank computes the summary's figures together (reductions over the ranks); rank 0 writes
history.csv, summary.json and design.vtu: the design variables ``x`` and the densities ρ̄
gathered per element, and the displacement ``u`` and the pressure ``p`` at the vertices, onto
the serial mesh it meshed, with the model's strain and stress measures per element
(:func:`pacto_ng.outputs.measure_fields`), and design.png, convergence.png and (3D) pressure.png
drawn on it.  Not yet written on a distributed mesh: pressure.png in 2D, materials.png and the
summary's leak figures of :func:`pacto_ng.outputs.write_outputs` (``pacto evaluate RUN`` of the
run's checkpoint, serially, writes them).
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from .files import atomic_path, atomic_write_text
from .outputs import measure_fields, run_summary, write_history, write_pictures


def write_distributed_outputs(path: Path, problem, x: np.ndarray, history: list, result,
                              wall: float, *, write: bool) -> dict:
    """The summary of the run (every rank: collective), and on the rank that ``write``s its
    files; returns the summary."""
    numbering, vals = problem.numbering, problem.values
    summ = run_summary(problem, history, result, wall)
    summ["mpi"] = {"ranks": numbering.comm.size, "elements_per_rank": numbering.counts}
    summ["mesh"] = {"elements": numbering.ne, "h": problem.h, "order": problem.params.order,
                    "dim": problem.mesh.dim,
                    "displacement_dofs": int(problem.mech.ndof)}
    rho = numbering.gather(np.asarray(vals.get("rho_bar", vals.get("rho_bar1")), dtype=float))
    xs = None
    if problem.n_design_fields == 1:
        xs = numbering.gather(problem.field.full(problem.design_numbering.local(x)))
    cells = {"rho_bar": rho, "x": xs}
    cells.update({name: numbering.gather(arr) for name, arr in measure_fields(problem).items()})
    mech, points = problem.mech, {}
    points["u"] = _vertex_field(numbering, problem.mesh, mech.u, problem.mesh.dim)
    if problem.pressure_block is not None:
        points["p"] = _vertex_field(numbering, problem.mesh, problem.pressure_block.pressure, 1)
    if not write:
        return summ
    write_history(path / "history.csv", history, problem)
    _write_vtu(path / "design.vtu", numbering, cells, points)
    title = f"{problem.case.name} - {problem.params.model}, volume {summ['volume_fraction']:.3f}"
    p_rel = None if "p" not in points else points["p"].ravel() / (problem.pressure_block.p_in
                                                                 or 1.0)
    write_pictures(path, problem, history,  # on the serial mesh, not mirrored
                   gathered=(numbering.serial_points, numbering.serial_cells, rho, title, p_rel))
    atomic_write_text(path / "summary.json", json.dumps(summ, indent=1))  # last: the run is done
    return summ


def _vertex_field(numbering, mesh, gf, comps: int) -> np.ndarray | None:
    """The values of the H1 field ``gf`` (``comps`` components) at the serial mesh's vertices,
    on rank 0 (None on the others): every rank sends its vertices' coordinates and values (a
    cumulated field: a shared vertex has one value), rank 0 places them by coordinates."""
    from ngsolve import VERTEX, NodeId
    from scipy.spatial import cKDTree

    vec, space = gf.vec.FV().NumPy(), gf.space
    pts = np.array([v.point for v in mesh.vertices], dtype=float).reshape(-1, mesh.dim)
    vals = np.array([vec[list(space.GetDofNrs(NodeId(VERTEX, i)))[:comps]]
                     for i in range(mesh.nv)], dtype=float).reshape(-1, comps)
    parts = numbering.comm.gather((pts, vals), root=0)
    if numbering.comm.rank != 0:
        return None
    serial = numbering.serial_points
    out = np.full((len(serial), comps), np.nan)
    tree = cKDTree(serial)
    for p, v in parts:
        if len(p):
            out[tree.query(p)[1]] = v
    return out


def _write_vtu(target: Path, numbering, fields: dict, points: dict) -> None:
    """The serial mesh with element and vertex fields (meshio; written atomically)."""
    import meshio

    cells = numbering.serial_cells
    kind = {(3, 4): "tetra", (3, 8): "hexahedron", (2, 3): "triangle",
            (2, 4): "quad"}[(numbering.serial_points.shape[1], cells.shape[1])]
    data = {name: [arr] for name, arr in fields.items() if arr is not None}
    xyz = numbering.serial_points
    if xyz.shape[1] == 2:  # VTU's points are 3D
        xyz = np.c_[xyz, np.zeros(len(xyz))]
    mesh = meshio.Mesh(xyz, [(kind, cells)], cell_data=data,
                       point_data={name: arr for name, arr in points.items()})
    with atomic_path(target) as tmp:
        meshio.write(str(tmp), mesh, file_format="vtu")
