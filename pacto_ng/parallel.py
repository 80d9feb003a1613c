"""One design on an MPI-distributed mesh: the reductions the blocks need, whatever the ranks.

Every helper takes the NGSolve mesh and reduces over its communicator (``mesh.comm``), which
is a single rank on a serial mesh: the same code runs serially and distributed.  On a
distributed mesh (netgen's ``Mesh.Distribute``) rank 0 holds no element; the other ranks hold
one part each, and a degree of freedom on a part's boundary exists on every rank that shares
it.  Element-wise arrays (densities, their sensitivities) are local; a sum over the elements is
the sum of the ranks' local sums.

NGSolve reduces some results itself and not others (measured, NGSolve 6.2.2608, 3 ranks):
``Integrate(cf, mesh)`` (also with ``definedon``) returns the whole mesh's integral on every
rank, ``Integrate(cf * dx, mesh)`` the local part's only (wrap it in :func:`total`);
``InnerProduct`` and ``Norm`` of parallel vectors are global; a matrix ``Inverse`` on a
distributed mesh is a ``MasterInverse`` (gathered on rank 0), with no numeric ``Update``.
"""
from __future__ import annotations

import os

import numpy as np

from .errors import InputError
from .mesh import Meshed


def world():
    """mpi4py's ``COMM_WORLD`` when this process is one of several ranks started by
    ``mpirun`` (``mpiexec``), else None (a serial run)."""
    size = int(os.environ.get("OMPI_COMM_WORLD_SIZE") or os.environ.get("PMI_SIZE") or 1)
    if size <= 1:
        return None
    try:
        from mpi4py import MPI
    except ImportError:
        raise InputError(f"started by mpirun with {size} ranks, but mpi4py is not installed: "
                         "python3 -m pip install '.[mpi]' (README, \"MPI\")") from None
    return MPI.COMM_WORLD


def leads() -> bool:
    """Whether this process writes a run's files: a serial run, or rank 0 of an MPI run."""
    comm = world()
    return comm is None or comm.rank == 0


def distributed(mesh) -> bool:
    """Is ``mesh`` one part of a mesh distributed over several ranks?"""
    return mesh.comm.size > 1


def total(mesh, value: float) -> float:
    """The sum over the ranks of a local sum (over the local elements)."""
    return float(mesh.comm.Sum(float(value))) if distributed(mesh) else float(value)


def bounding_box(mesh) -> tuple[np.ndarray, np.ndarray]:
    """The corners (min, max) of the whole mesh's vertices."""
    pts = np.array([v.point for v in mesh.vertices], dtype=float).reshape(-1, mesh.dim)
    lo = pts.min(axis=0) if len(pts) else np.full(mesh.dim, np.inf)
    hi = pts.max(axis=0) if len(pts) else np.full(mesh.dim, -np.inf)
    if distributed(mesh):
        lo = np.array([mesh.comm.Min(float(a)) for a in lo])
        hi = np.array([mesh.comm.Max(float(a)) for a in hi])
    return lo, hi


def everywhere(mesh, ok: bool) -> bool:
    """Whether ``ok`` holds on every rank (a test of the local part, e.g. admissibility)."""
    return bool(mesh.comm.Min(int(bool(ok)))) if distributed(mesh) else bool(ok)


def free_norm(vec, free: np.ndarray) -> float:
    """The Euclidean norm of an NGSolve vector over the free dofs (the local mask ``free``):
    numpy on a serial vector; on a distributed one NGSolve's ``Norm``, which counts a dof that
    several ranks share once, whether the vector is cumulated or distributed."""
    from ngsolve.la import PARALLEL_STATUS

    if vec.GetParallelStatus() == PARALLEL_STATUS.NOT_PARALLEL:
        return float(np.linalg.norm(vec.FV().NumPy()[free]))
    masked = vec.CreateVector()
    masked.data = vec
    masked.FV().NumPy()[~free] = 0.0
    return float(masked.Norm())


def element_centroids(mesh) -> np.ndarray:
    """The centroid of every local volume element, in NGSolve's order."""
    pts = np.array([v.point for v in mesh.vertices], dtype=float).reshape(-1, mesh.dim)
    return np.array([pts[[v.nr for v in el.vertices]].mean(axis=0) for el in mesh.Elements()],
                    dtype=float).reshape(-1, mesh.dim)


class Numbering:
    """Where each rank's local elements sit in the serial mesh's element order.

    Made by :func:`distribute`: rank 0 keeps the serial mesh's element centroids, every rank
    sends its local ones, and rank 0 matches them (nearest centroid; the distance is checked
    to be round-off).  :meth:`gather` and :meth:`scatter` move element-wise arrays between
    the ranks' local order and the serial order on rank 0, the order of the design vector that
    MMA, the checkpoint and the output files see, whatever the number of ranks."""

    def __init__(self, comm, local: np.ndarray, counts: list[int] | None, ne: int):
        self.comm, self.local, self.counts, self.ne = comm, local, counts, ne
        # rank 0: the serial mesh it meshed, a copy kept whole for the files it writes (the
        # pictures and figures of one serial mesh, as a serial run's); None elsewhere
        self.serial_mesh = None

    @classmethod
    def match(cls, comm, mesh, serial_centroids: np.ndarray | None):
        from scipy.spatial import cKDTree

        parts = comm.gather(element_centroids(mesh), root=0)
        numbers, counts, ne = None, None, 0
        if comm.rank == 0:
            ne = len(serial_centroids)
            tree = cKDTree(serial_centroids)
            scale = float(np.ptp(serial_centroids, axis=0).max())
            numbers, counts = [], []
            for part in parts:
                dist, idx = tree.query(part) if len(part) else (np.zeros(0), np.zeros(0, int))
                if len(part) and dist.max() > 1e-9 * scale:
                    raise RuntimeError("a distributed element matches no serial element")
                numbers.append(np.asarray(idx, dtype=np.int64))
                counts.append(len(part))
            if sorted(np.concatenate(numbers).tolist()) != list(range(ne)):
                raise RuntimeError("the distributed elements are not the serial mesh's")
        local = comm.scatter(numbers, root=0)
        return cls(comm, local, counts, comm.bcast(ne, root=0))

    def gather(self, values: np.ndarray) -> np.ndarray | None:
        """The element-wise local ``values`` of every rank, in serial order on rank 0 (None
        on the others)."""
        parts = self.comm.gather(np.asarray(values, dtype=float), root=0)
        numbers = self.comm.gather(self.local, root=0)
        if self.comm.rank != 0:
            return None
        out = np.empty(self.ne)
        for idx, part in zip(numbers, parts):
            out[idx] = part
        return out

    def least(self, entry: dict, key: str) -> dict:
        """The ``entry`` of the least ``key`` over the ranks, on every rank, its ``element``
        (a local index on the rank that gives it, -1: none) in the serial order."""
        if entry["element"] >= 0:
            entry = dict(entry, element=int(self.local[entry["element"]]))
        return min(self.comm.allgather(entry), key=lambda e: e[key])

    def allgather(self, values: np.ndarray) -> np.ndarray:
        """The element-wise local ``values`` of every rank, in serial order on every rank."""
        out = np.empty(self.ne)
        for idx, part in self.comm.allgather((self.local, np.asarray(values, dtype=float))):
            out[idx] = part
        return out

    def scatter(self, values: np.ndarray | None) -> np.ndarray:
        """The local part of the serial-order ``values`` given on rank 0."""
        values = self.comm.bcast(None if values is None else np.asarray(values, dtype=float),
                                 root=0)
        return values[self.local]


def distribute(meshed, comm):
    """A meshed domain (:class:`~pacto_ng.mesh.Meshed`) distributed over ``comm``
    (mpi4py): rank 0 passes the serial one, the others ``None``; each rank gets its part
    (rank 0 none: netgen's convention) and the :class:`Numbering` of its elements."""
    import ngsolve
    from netgen.meshing import Mesh as NGMesh

    serial = None
    if comm.rank == 0:
        centroids = element_centroids(meshed.mesh)
        h, shape = comm.bcast(meshed.h, root=0), meshed.shape
        ngm = meshed.mesh.ngmesh
        serial = ngsolve.Mesh(ngm.Copy())  # Distribute empties rank 0's mesh
        ngm.Distribute(comm)
    else:
        centroids, shape = None, None
        h = comm.bcast(None, root=0)
        ngm = NGMesh.Receive(comm)
    part = Meshed(ngsolve.Mesh(ngm), h, shape)
    numbering = Numbering.match(comm, part.mesh, centroids)
    numbering.serial_mesh = serial
    return part, numbering


def largest(mesh, values: np.ndarray) -> float:
    """The largest of the local ``values`` of every rank (-inf where there are none)."""
    local = float(np.max(values)) if np.size(values) else -np.inf
    return float(mesh.comm.Max(local)) if distributed(mesh) else local


class DesignNumbering:
    """The design variables of a distributed mesh in the serial run's order.

    The optimiser, the checkpoint and the output files see the serial design vector (one
    variable per design element of the serial mesh, in its order, per material): every rank
    holds all of it, takes its local part for its blocks (:meth:`local`) and puts its local
    gradients back (:meth:`whole`), so that a run's history does not depend on the ranks."""

    def __init__(self, numbering: Numbering, field):
        design = numbering.allgather(field.design.astype(float)) > 0.5
        position = np.full(numbering.ne, -1)
        position[design] = np.arange(int(design.sum()))
        self.comm, self.n = numbering.comm, int(design.sum())
        self.positions = position[numbering.local[field.design_index]]

    def local(self, x: np.ndarray) -> np.ndarray:
        """This rank's part of the serial design vector ``x`` (every material's block); the
        vector is rank 0's, so that every rank works on the same design."""
        x = self.comm.bcast(np.asarray(x, dtype=float), root=0)
        blocks = x.reshape(-1, self.n)
        return blocks[:, self.positions].ravel()

    def whole(self, g: np.ndarray, fields: int = 1) -> np.ndarray:
        """The serial design vector's gradient (``fields`` materials) from every rank's local
        ``g``."""
        out = np.zeros((fields, self.n))
        for pos, part in self.comm.allgather((self.positions,
                                              np.asarray(g, dtype=float).reshape(fields, -1))):
            out[:, pos] = part
        return out.ravel()


def all_rows(mesh, rows: np.ndarray) -> np.ndarray:
    """Every rank's local ``rows`` (an array of shape (n, k)) stacked, on every rank."""
    rows = np.asarray(rows, dtype=float)
    if not distributed(mesh):
        return rows
    return np.concatenate(mesh.comm.mpi4py.allgather(rows))


def union(mesh, values: np.ndarray) -> np.ndarray:
    """The sorted distinct values of every rank's local ``values``, on every rank."""
    values = np.unique(np.asarray(values, dtype=float))
    if not distributed(mesh):
        return values
    return np.unique(np.concatenate(mesh.comm.mpi4py.allgather(values)))
