"""The Krylov solves of :class:`~pacto_ng.physics.solvers.LinearSolver`'s iterative route:
NGSolve's CG, and the loops its solvers do not provide as needed, GMRES restarted within a
bounded number of iterations and CG stopped on the Euclidean norm of its residual on the free
dofs."""
from __future__ import annotations

from dataclasses import dataclass

from ngsolve import InnerProduct
from ngsolve.krylovspace import CGSolver, GMResSolver

from ..parallel import free_norm


@dataclass
class KrylovRun:
    """A Krylov solve's method, iterations and residual norms (the first the initial one)."""

    name: str
    iterations: int
    residuals: list


def cg(mat, pre, rhs, out, tol: float, maxiter: int) -> KrylovRun:
    """NGSolve's preconditioned CG from ``out = 0`` to ``tol`` of the first preconditioned
    residual, at most ``maxiter`` iterations."""
    krylov = CGSolver(mat, pre, tol=tol, maxiter=maxiter)
    krylov.Solve(rhs=rhs, sol=out)
    return KrylovRun("CGSolver", krylov.iterations, list(krylov.residuals))


def gmres(mat, pre, rhs, out, tol: float, maxiter: int, restart: int) -> KrylovRun:
    """GMRES from ``out = 0``, restarted every ``restart`` iterations, until the
    preconditioned residual is ``tol`` times the first or ``maxiter`` iterations are spent.
    NGSolve's own restart starts each cycle with a fresh iteration count, so that a stagnating
    solve never stops (it ended in a RecursionError); here each cycle is one solve of at most
    the iterations left, from where the last ended."""
    out[:] = 0.0
    residuals, its, target = [], 0, None
    while its < maxiter:
        cycle = GMResSolver(mat, pre, tol=tol if target is None else 0.0, atol=target,
                            maxiter=min(restart, maxiter - its))
        cycle.Solve(rhs=rhs, sol=out, initialize=False)
        its += cycle.iterations
        if not cycle.residuals:
            break
        residuals += cycle.residuals if target is None else cycle.residuals[1:]
        if target is None:
            target = tol * residuals[0]
        if residuals[0] == 0 or residuals[-1] <= target or cycle.iterations < cycle.maxiter:
            break  # converged, or an Arnoldi breakdown (the solution exact)
    return KrylovRun("GMRESSolver", its, residuals)


def cg_to_residual(mat, pre, rhs, out, target: float, free, maxiter: int) -> KrylovRun:
    """Preconditioned CG from ``out = 0`` (``rhs`` zero on the fixed dofs, and overwritten by
    the final residual: the caller's working copy) that stops once
    the Euclidean norm of its residual on the free dofs (the mask ``free``; updated by the
    recurrence) is at most ``target``, not on the preconditioned norm NGSolve's CG measures:
    with BDDC the two differed by a factor of about 300 on the cantilever-3d, so that a solve
    to Newton's tolerance in the preconditioned norm left a residual that Newton's test
    refused, and cost a second solve (20 CG iterations and a residual each design, measured at
    603 528 dofs).  Its residuals: the first and the last."""
    r = rhs
    z, p, w = (rhs.CreateVector() for _ in range(3))
    out[:] = 0.0
    first = norm = free_norm(r, free)
    its = 0
    if norm > target:
        z.data = pre * r
        p.data = z
        rz = InnerProduct(r, z)
        while its < maxiter:
            w.data = mat * p
            alpha = rz / InnerProduct(p, w)
            out.data += alpha * p
            r.data -= alpha * w
            its += 1
            norm = free_norm(r, free)
            if norm <= target:
                break
            z.data = pre * r
            rz, rz_old = InnerProduct(r, z), rz
            p *= rz / rz_old
            p.data += z
    return KrylovRun("CGSolver", its, [first, norm])
