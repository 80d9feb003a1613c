"""The results of a run on a distributed mesh (:mod:`pacto_ng.parallel`), written by rank 0.

Every rank computes the summary's figures together (reductions over the ranks); rank 0 writes
history.csv, summary.json and design.vtu: the design variables ``x`` and the densities ρ̄
gathered per element onto the serial mesh it meshed, in the serial order.  Not yet written on a
distributed mesh: the displacement and pressure fields, the strain and stress fields and the
pictures of :func:`pacto_ng.outputs.write_outputs` (``pacto evaluate RUN`` of the run's
checkpoint, serially, writes them).
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from .files import atomic_path, atomic_write_text
from .outputs import write_history


def write_distributed_outputs(path: Path, problem, x: np.ndarray, history: list, result,
                              wall: float, *, write: bool) -> dict:
    """The summary of the run (every rank: collective), and on the rank that ``write``s its
    files; returns the summary."""
    numbering, vals = problem.numbering, problem.values
    summ = {
        "case": problem.case.name,
        "model": problem.params.model,
        "parameters": problem.params.to_dict(),
        "load": problem.params.load,
        "load_unit": problem.case.load_unit,
        "iterations": len(history),
        "objective": float(vals[problem.objective]),
        "objective_name": problem.objective,
        "objective_history": [h["objective"] for h in history],
        "volume_fraction": problem.volume_fraction(),
        "greyness": problem.greyness(),
        "converged": bool(result.converged),
        "stopped": result.stopped,
        "message": result.message,
        "wall_time_s": wall,
        "mpi": {"ranks": numbering.comm.size, "elements_per_rank": numbering.counts},
        "mesh": {"elements": numbering.ne, "h": problem.h, "order": problem.params.order,
                 "dim": problem.mesh.dim,
                 "displacement_dofs": int(problem.mech.fes.ndofglobal)},
    }
    rho = numbering.gather(np.asarray(vals.get("rho_bar", vals.get("rho_bar1")), dtype=float))
    xs = None
    if problem.n_design_fields == 1:
        xs = numbering.gather(problem.field.full(problem.design_numbering.local(x)))
    if not write:
        return summ
    write_history(path / "history.csv", history, problem)
    _write_vtu(path / "design.vtu", numbering, {"rho_bar": rho, "x": xs})
    atomic_write_text(path / "summary.json", json.dumps(summ, indent=1))  # last: the run is done
    return summ


def _write_vtu(target: Path, numbering, fields: dict) -> None:
    """The serial mesh with element fields (meshio; written atomically)."""
    import meshio

    cells = numbering.serial_cells
    kind = {(3, 4): "tetra", (3, 8): "hexahedron", (2, 3): "triangle",
            (2, 4): "quad"}[(numbering.serial_points.shape[1], cells.shape[1])]
    data = {name: [arr] for name, arr in fields.items() if arr is not None}
    mesh = meshio.Mesh(numbering.serial_points, [(kind, cells)], cell_data=data)
    with atomic_path(target) as tmp:
        meshio.write(str(tmp), mesh, file_format="vtu")
