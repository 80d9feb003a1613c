"""What a mesh and a run on it will cost, in the terms both halves of the resources check share:
the :class:`Estimate` record (:mod:`pacto_ng.resources`, 2D and 3D meshes), the memory of a mesh (:func:`mesh_bytes`) and a run's memory around its
displacement system (:func:`run_overheads`).

Around the system (assembled and factorised, each dimension's fit) a run holds the mesh
(``_MESH_BYTES`` per element, 860 measured at 185k triangles), the linear fast paths' element
matrices while they are built (about 88 bytes per entry, built only below 20·10⁶ entries:
physics/scatter.py; counted for the displacement and a Darcy pressure in every case, an
over-estimate for cases without them; on the iterative route the displacement's up to 10⁸
entries, 30 bytes each: physics/linear_system.py), and the pressure's and filter's systems,
MMA and the outputs (``_RUN_FACTOR`` = 1.25 on the system; checked on whole runs in
:mod:`pacto_ng.resource_probes`).
"""
from __future__ import annotations

from dataclasses import dataclass

_MESH_BYTES = 1000.0        # per element of the mesh (Netgen + NGSolve; 860 measured at 185k)
_RUN_FACTOR = 1.25          # a whole run over its displacement system (module docstring)
_SCATTER_BYTES = 88.0       # per entry of the fast paths' element matrices, while built
_SCATTER_MAX = 20_000_000   # entries above which they are not built (physics/scatter.py)
# the displacement's on the iterative route (physics/linear_system.py ITERATIVE_MAX_ENTRIES),
# where they let BDDC be kept across designs: 30.4 bytes per entry at the peak of their build,
# 19 resident after it (cantilever-3d, 228,318 dofs, 45.5e6 entries: 0.91 -> 2.19 GB peak)
_ITERATIVE_SCATTER_BYTES = 30.0
_ITERATIVE_SCATTER_MAX = 100_000_000


@dataclass(frozen=True)
class Estimate:
    """What a mesh will cost: ``elements``, displacement ``dofs`` at ``order`` (0: the mesh
    alone, no analysis on it), a run's peak
    ``memory`` (bytes above the process's start) and the ``mesh_seconds`` its ``mesher``
    (``Netgen``, ``the grid builder``; None for a mesh that exists) takes.  ``kind``:
    ``triangles``, ``quads``, ``tetrahedra``, ``hexahedra`` or ``elements`` (mixed);
    ``exact``: elements and dofs counted, not estimated (a structured grid, a mesh that
    exists)."""

    elements: float
    dofs: float
    memory: float
    mesh_seconds: float
    order: int
    kind: str
    mesher: str | None
    exact: bool = False


def mesh_bytes(elements: float) -> float:
    """The memory of a mesh of ``elements`` elements (Netgen + NGSolve), as the fits count it."""
    return _MESH_BYTES * elements


def run_overheads(system: float, elements: float, local: float, *, dim: int,
                  iterative: bool = False) -> float:
    """A run's memory around its displacement ``system`` (bytes, assembled and factorised):
    the system times ``_RUN_FACTOR``, the mesh, and the linear fast paths' element matrices
    for ``local`` scalar dofs per element (a ``dim``-vector displacement's, and the Darcy
    pressure's two matrices; none above their budget, which is larger for the displacement on
    the ``iterative`` route)."""
    scatter = 0.0
    darcy = 2 * elements * local ** 2  # Darcy K, D
    displacement = elements * (dim * local) ** 2
    for entries in (darcy, displacement) if not iterative else (darcy,):
        if entries <= _SCATTER_MAX:  # above it the fast path is not built
            scatter += _SCATTER_BYTES * entries
    if iterative and displacement <= _ITERATIVE_SCATTER_MAX:
        scatter += _ITERATIVE_SCATTER_BYTES * displacement
    return _RUN_FACTOR * system + mesh_bytes(elements) + scatter
