"""The results of a run on a distributed mesh (:mod:`pacto_ng.parallel`), written by rank 0.

Every rank computes the summary of :func:`pacto_ng.outputs.summary_dict` together (its
figures reduced over the ranks); the element fields are gathered to rank 0, onto the serial
mesh it meshed and kept (:attr:`~pacto_ng.parallel.Numbering.serial_mesh`), with the
displacement and the pressure at its vertices, and rank 0 writes what a serial run writes
of the same fields: history.csv, summary.json (the serial run's figures, the leakage and a
two-material design's fractions made on that mesh, and ``mpi``), design.vtu (``x``, ρ̄,
``u``, ``p`` and the model's strain and stress measures,
:func:`pacto_ng.outputs.measure_fields`) and the pictures of
:func:`pacto_ng.outputs.write_pictures` (design.png mirrored where the case is a half,
pressure.png, materials.png, convergence.png).
"""
from __future__ import annotations

import json
from pathlib import Path

import meshio
import numpy as np
from ngsolve import VERTEX, Integrate, NodeId
from scipy.spatial import cKDTree

from .files import atomic_path, atomic_write_text
from .outputs import (DENSITIES, OneMesh, cell_names, drawn, measure_fields, summary_dict,
                      write_history, write_pictures)


def write_distributed_outputs(path: Path, problem, x: np.ndarray, history: list, result,
                              wall: float, *, write: bool) -> dict:
    """The summary of the run (every rank: collective), and on the rank that ``write``s its
    files; returns the summary (the whole on that rank)."""
    numbering, vals, block = problem.numbering, problem.values, problem.pressure_block
    cells = {name: numbering.gather(np.asarray(vals[name], dtype=float))
             for name in cell_names(problem)}
    design = numbering.gather(problem.field.design.astype(float))
    xs = None
    if problem.n_design_fields == 1:
        xs = numbering.gather(problem.field.full(problem.design_numbering.local(x)))
    fields = {name: numbering.gather(arr) for name, arr in measure_fields(problem).items()}
    points = {"u": _vertex_field(numbering, problem.mesh, problem.mech.u, problem.mesh.dim)}
    if block is not None:
        points["p"] = _vertex_field(numbering, problem.mesh, block.pressure, 1)
    one = None
    if numbering.comm.rank == 0:
        serial = numbering.serial_mesh
        one = OneMesh(serial, cells, design > 0.5,
                      np.array(Integrate(1.0, serial, element_wise=True)),
                      None if block is None else points["p"].ravel())
    summ = summary_dict(problem, history, result, wall, one)
    if not write:
        return summ
    write_history(path / "history.csv", history, problem)
    densities = {name: cells[name] for name in DENSITIES if name in cells}
    _write_vtu(path / "design.vtu", one.mesh, {**densities, "x": xs, **fields}, points)
    write_pictures(path, drawn(problem, one, summ), history, problem.objective)
    atomic_write_text(path / "summary.json", json.dumps(summ, indent=1))  # last: the run is done
    return summ


def _vertex_field(numbering, mesh, gf, comps: int) -> np.ndarray | None:
    """The values of the H1 field ``gf`` (``comps`` components) at the serial mesh's vertices,
    on rank 0 (None on the others): every rank sends its vertices' coordinates and values (a
    cumulated field: a shared vertex has one value), rank 0 places them by coordinates."""
    vec, space = gf.vec.FV().NumPy(), gf.space
    pts = _points(mesh)
    vals = np.array([vec[list(space.GetDofNrs(NodeId(VERTEX, i)))[:comps]]
                     for i in range(mesh.nv)], dtype=float).reshape(-1, comps)
    parts = numbering.comm.gather((pts, vals), root=0)
    if numbering.comm.rank != 0:
        return None
    serial = _points(numbering.serial_mesh)
    out = np.full((len(serial), comps), np.nan)
    tree = cKDTree(serial)
    for p, v in parts:
        if len(p):
            out[tree.query(p)[1]] = v
    return out


def _points(mesh) -> np.ndarray:
    """The vertex coordinates of ``mesh``, (n, dim)."""
    return np.array([v.point for v in mesh.vertices], dtype=float).reshape(-1, mesh.dim)


def _write_vtu(target: Path, mesh, fields: dict, points: dict) -> None:
    """The serial ``mesh`` with element and vertex fields (meshio; written atomically)."""
    cells = np.array([[v.nr for v in el.vertices] for el in mesh.Elements()], dtype=np.int64)
    kind = {(3, 4): "tetra", (3, 8): "hexahedron", (2, 3): "triangle",
            (2, 4): "quad"}[(mesh.dim, cells.shape[1])]
    data = {name: [arr] for name, arr in fields.items() if arr is not None}
    xyz = _points(mesh)
    if xyz.shape[1] == 2:  # VTU's points are 3D
        xyz = np.c_[xyz, np.zeros(len(xyz))]
    out = meshio.Mesh(xyz, [(kind, cells)], cell_data=data,
                      point_data={name: arr for name, arr in points.items()})
    with atomic_path(target) as tmp:
        meshio.write(str(tmp), out, file_format="vtu")
