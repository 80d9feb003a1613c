"""Which route a block's linear system takes, and BDDC's coarse space on the iterative one.

:func:`choose` takes the direct route in 2D and, in 3D, up to :data:`DIRECT_MAX_DOFS_3D` dofs
and for a vector space of order 1 (where every dof is a BDDC vertex dof, so that the
iterative route is a direct solve plus iterations); the scalar order-1 systems (Darcy, the
filter) take ``h1amg`` above the same number of dofs (:func:`preconditioner_for`).  The
threshold is measured by ``PACTO_THREADS=1 python3 -m benchmarks.solvers_3d``
(docs/studies.md, "3D solvers: direct against iterative"; see the constant's comment).
:func:`vertex_coarse_space` makes BDDC's coarse problem the vertex problem in 3D at order
>= 2.  :class:`~pacto_ng.physics.solvers.LinearSolver` solves on the route chosen.
"""
from __future__ import annotations

import numpy as np

from ..parallel import distributed

SOLVERS = ("auto", "direct", "iterative")

# Above this many dofs of a 3D system, ``auto`` takes the iterative route.  Measured
# (docs/studies.md, "3D solvers: direct against iterative": linear elasticity on a
# cantilever box at order 2, one linear solve with its assembly, one thread, CG + BDDC to
# 1e-8): the direct route is faster at 8 000 dofs (1.1 against 1.5 s), the iterative one at
# 25 000 (5.0 against 8.0 s) and 56 000 (3.4 against 25 s), with slopes of 2 against 1.
# An optimisation asks more of the iterative route than that solve: the adjoint is a second
# Krylov solve where the direct route reuses its factorisation, the tolerances of Newton's
# linear step and of the adjoint are tighter than 1e-8 (12 digits against 8 at CG's linear
# rate: about 1.5x the iterations, estimated), and SIMP's contrast adds some (measured: 57 ->
# 65 iterations at 25 000 dofs, E0 = 1e-6 E1, a 0/1 design).  Whole optimisation iterations
# favour the direct route further (docs/studies.md, "3D optimisation iterations", order 2,
# one thread): with the element-matrix assembly of linear runs it was the faster at every size
# measured, 8.6 against 11.3 s per iteration at 78 000 dofs (cantilever-3d) and 4.0 against
# 10.8 s at 50 000 (pneunet-3d); the fitted slopes (1.51 against 1.04, cantilever-3d) cross
# near 1.4e5 dofs, where the 3D Cholesky needs about 2 GB (pacto_ng/resources.py).
DIRECT_MAX_DOFS_3D = 140_000


def preconditioner_for(fes, order: int) -> str:
    """``"h1amg"`` for a scalar H1 space of order 1, ``"bddc"`` otherwise and on a distributed
    mesh (NGSolve's h1amg takes a serial matrix only)."""
    from ngsolve import H1

    return "h1amg" if type(fes) is H1 and order == 1 and not distributed(fes.mesh) else "bddc"


def choose(setting: str, ndof: int, dim: int, order: int, preconditioner: str = "bddc",
           parallel: bool = False) -> str:
    """``"direct"`` or ``"iterative"`` for a system of ``ndof`` dofs on a ``dim``-D mesh of
    element order ``order`` whose iterative route would use ``preconditioner`` (see the
    module); ``setting`` is ``auto``, ``direct`` or ``iterative``.  On a distributed mesh
    (``parallel``) ``auto`` is iterative: the direct route gathers the matrix on rank 0."""
    if setting not in SOLVERS:
        raise ValueError(f"solver must be one of {', '.join(SOLVERS)} (got '{setting}')")
    if setting != "auto":
        return setting
    if parallel:
        return "iterative"
    coarse_is_all = preconditioner == "bddc" and order == 1  # every dof a vertex dof
    if dim == 3 and not coarse_is_all and ndof > DIRECT_MAX_DOFS_3D:
        return "iterative"
    return "direct"


def vertex_coarse_space(fes, coarse=None):
    """Make the wirebasket dofs that are not on a vertex interface dofs, except those of the
    elements of the regions ``coarse`` (None: every boundary element): BDDC's coarse problem
    is then the vertex problem and those regions' dofs.  Such a region is where the form has
    boundary terms (a spring on a face): their element matrices are singular on its edge dofs,
    which BDDC would invert.  A form without boundary terms passes ``()``: on the cantilever
    box at order 2 the boundary's edges had held 64 % of the coarse dofs (32 358 against
    11 703 vertex dofs at 78 219 dofs) and doubled the time of a CG iteration."""
    from ngsolve import VERTEX, NodeId
    from ngsolve.comp import COUPLING_TYPE

    keep = np.zeros(fes.ndof, dtype=bool)
    for v in range(fes.mesh.nv):
        keep[[d for d in fes.GetDofNrs(NodeId(VERTEX, v)) if d >= 0]] = True
    for region in ((fes.mesh.Boundaries(".*"),) if coarse is None else coarse):
        keep |= np.array(list(fes.GetDofs(region)), dtype=bool)
    wirebasket = COUPLING_TYPE.WIREBASKET_DOF
    types = fes.couplingtype
    for d in np.flatnonzero(~keep):
        if types[d] == wirebasket:
            fes.SetCouplingType(int(d), COUPLING_TYPE.INTERFACE_DOF)
