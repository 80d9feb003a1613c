"""The linear solver of a block's system: a sparse direct factorisation while it fits, a
preconditioned Krylov solver beyond.

:class:`LinearSolver` solves ``A x = b`` (and ``Aᵀ x = b``, the adjoint) on the free dofs of a
:class:`ngsolve.BilinearForm`'s matrix, by one of two routes:

* ``direct``: ``sparsecholesky`` for a symmetric matrix, ``umfpack`` otherwise (or the
  ``inverse`` given); factorised once per matrix (:meth:`LinearSolver.prepare`: ``Inverse``,
  then a numeric ``Update`` for every new matrix of the same structure); the transpose solve
  uses the same factorisation;
* ``iterative``: NGSolve's CG (symmetric) or GMRES (unsymmetric) with a preconditioner
  registered on the form *before* it is assembled (it is built from the element matrices
  during ``Assemble``/``AssembleLinearization``, so a matrix written by other means, e.g. the
  element-matrix scatter, must not be used with it): BDDC for vector spaces and higher
  orders, ``h1amg`` for a scalar order-1 space (the Darcy pressure at order 1, the Helmholtz
  filter).  In 3D at order >= 2 the edges' dofs are made interface dofs, except on the
  regions where the form has boundary terms (a spring's face), so that BDDC's coarse
  (wirebasket) problem is the vertex problem (an eighth of the dofs), solved by a direct
  factorisation; with NGSolve's default (edges in the wirebasket) every order-2 dof is
  coarse and BDDC is a direct solve.  A nonlinear model's tangent changes at every Newton
  step, and away from rest it can be indefinite (crushed void elements, compression), where
  BDDC built on it fails (CG diverged on the Neo-Hookean cantilever-3d at its full load): its
  preconditioner is BDDC built once per design on the same tangent at rest (the design's
  small-strain stiffness, symmetric positive definite), and its Newton steps and adjoint are
  solved with it (CG, or GMRES for an unsymmetric tangent).  The transpose
  solve (an unsymmetric adjoint) is GMRES on ``Aᵀ`` with the same preconditioner (it
  approximates ``A⁻¹``; the follower tangent is a perturbation of a symmetric one).

The route (``auto``: direct in 2D and in 3D up to a size) is chosen by
:func:`~pacto_ng.physics.routes.choose`.  On the iterative route a linear system's
preconditioner is kept across designs while it serves them well (``refresh``;
:mod:`~pacto_ng.physics.reuse`).

The Krylov tolerance is relative to the right-hand side's (preconditioned) norm; the caller
ties it to what it needs (Newton: its own residual test, whose tolerance on this route is
1e-6 of the load unless set, :data:`~pacto_ng.physics.newton.ITERATIVE_RTOL`; the adjoint:
a tenth of Newton's, :func:`adjoint_rtol`; the Darcy and filter solves:
:data:`ADJOINT_RTOL`.  ``pacto check-gradients`` tightens Newton's to 1e-12, and with it the
adjoint's, for the finite-difference checks; tests/physics/test_solvers.py).
:attr:`LinearSolver.info` describes the route for the run summary.
"""
from __future__ import annotations

import numpy as np

from ..parallel import distributed
from .krylov import KrylovRun, cg, cg_to_residual, gmres
from .routes import choose, preconditioner_for, vertex_coarse_space
from .reuse import Reuse

ADJOINT_RTOL = 1e-12  # Krylov tolerance of the Darcy and filter solves (relative)
MAX_ITERATIONS = 1000
GMRES_RESTART = 100  # GMRES keeps this many Krylov vectors at most (8 MB each per 1e6 dofs)
#: a matrix assembled near the one factorised (Newton's tangent at the converged state, after
#: the tangent of its last full step; a sweep's tangents, after the last load's) is solved by
#: CG / GMRES with that factorisation as the preconditioner, to this relative tolerance (or
#: the looser one a Newton step asks for), in at most STALE_ITERATIONS; where it needs more,
#: the matrix is factorised
STALE_RTOL = 1e-12
STALE_ITERATIONS = 10
#: a Newton step solved so is solved to at most this relative tolerance (its forcing term,
#: Equilibrium.solve_tangent, at most this): such a Krylov iteration (two triangular solves)
#: costs a fraction of the tangent's assembly, while a looser solve made the Newton steps chord
#: steps (pneunet-3d's part at 32 kPa: 16 Newton iterations at 1e-2 against 9 factorised)
STALE_FORCING = 1e-6
#: ... and one solved by GMRES with BDDC built on the tangent at rest (``at_rest``): GMRES on
#: the symmetric Neo-Hookean tangent of cantilever-3d (maxh 0.06, order 2, a random design)
#: took 34 Newton iterations at 1e-2, 9 at 1e-4 and 1e-6, as BDDC on each tangent did; CG
#: with the same preconditioner took 8 at 1e-2, 1e-4 and 1e-6 (CG keeps 1e-2)
AT_REST_FORCING = 1e-4


def adjoint_rtol(newton_rtol: float) -> float:
    """The Krylov tolerance of an adjoint solve with the tangent Newton solved to
    ``newton_rtol``: a tenth of it, never below :data:`ADJOINT_RTOL`, so that the gradient's
    error is the equilibrium's.  The gradient errors of docs/studies.md ("The iterative
    route's tolerance", pneunet-3d: 1.9e-6 of the largest entry at Newton's 1e-6) are of both
    solves together."""
    return max(ADJOINT_RTOL, 0.1 * newton_rtol)


class SolverFailure(RuntimeError):
    """A Krylov solve that did not reach its tolerance within its iterations."""


class LinearSolver:
    """Solves with the matrix of ``form`` on ``freedofs`` (see the module).

    Parameters
    ----------
    form : ngsolve.BilinearForm
        Not yet assembled when the route is iterative (its preconditioner is registered here).
    freedofs : BitArray or None
        The free dofs (None: every dof).
    setting : str
        ``auto``, ``direct`` or ``iterative`` (:func:`choose`).
    symmetric : bool
        CG and ``sparsecholesky`` for a symmetric matrix, GMRES and ``umfpack`` otherwise.
    order : int
        The element order of the form's space (the choice and the preconditioner).
    inverse : str or None
        The direct solver (default by symmetry).
    rtol : float
        Default Krylov tolerance (relative to the right-hand side).
    coarse : sequence of ngsolve Regions, or None
        In 3D at order >= 2, the regions (boundaries, edges, points) where the form has
        boundary terms, whose dofs stay in BDDC's coarse space (None: every boundary; see
        :func:`_vertex_coarse_space`).
    at_rest : callable or None
        A nonlinear tangent's: makes a second form of the same tangent.  On the iterative
        route the preconditioner is built on it, linearised at rest (``u = 0``: the design's
        small-strain stiffness) once per design (:meth:`new_design`), and the tangents of the
        design's Newton steps and its adjoint are solved with it (see the module).
    refresh : callable or None
        A linear system's: assembles the form's matrix by the form for the current design
        (its preconditioner set up again).  On the iterative route the preconditioner is then
        kept across designs, whose matrices the owner writes by other means while
        :attr:`rebuild_due` is False, and rebuilt by this where a solve needs it
        (:mod:`~pacto_ng.physics.reuse`).
    """

    def __init__(self, form, freedofs=None, *, setting: str = "auto", symmetric: bool = True,
                 order: int = 1, inverse: str | None = None, rtol: float = ADJOINT_RTOL,
                 coarse=None, at_rest=None, refresh=None):
        from ngsolve import Preconditioner

        fes = form.space
        self.form, self.freedofs, self.symmetric = form, freedofs, bool(symmetric)
        pre = preconditioner_for(fes, order)
        self.kind = choose(setting, fes.ndof, fes.mesh.dim, order, pre, distributed(fes.mesh))
        self.setting = setting
        self.inverse = inverse or ("sparsecholesky" if self.symmetric else "umfpack")
        self.rtol = float(rtol)
        self.preconditioner = None
        self._pre = None
        self._inv = None
        self._factorised = None  # the matrix _inv factorises
        self._stale = False  # the matrix's values changed since _inv factorised it
        self.stale_solves = 0  # solves preconditioned by the factorisation of an earlier matrix
        self.stale_failed = 0  # ... of them that needed the matrix factorised after all
        self._condensed_rhs = None
        self._rest_form = None  # the form the preconditioner is built on at rest (at_rest)
        self._rest_stale = True  # ... not yet assembled for this design
        self.rest_builds = 0  # ... assemblies of it (once per design)
        self._refresh = refresh
        self.reuse = None  # a preconditioner kept across designs (reuse.py)
        self._free = None  # the free dofs as a numpy mask (_cg_to_residual)
        self.iterations = 0  # Krylov iterations of the last solve
        self.total_iterations = 0
        self.solves = 0
        if self.direct and not self.symmetric and distributed(fes.mesh):
            raise ValueError("an unsymmetric matrix (the follower load's tangent) on a "
                             "distributed mesh: its direct solver (NGSolve's MasterInverse) "
                             "has no transposed solve for the adjoint; use --set "
                             "solver=iterative (the default there)")
        if self.kind == "iterative":
            self.preconditioner = pre
            if self.preconditioner == "bddc" and fes.mesh.dim == 3 and order >= 2:
                vertex_coarse_space(fes, coarse)
            if at_rest is not None:
                self._rest_form = at_rest()
            self._pre = Preconditioner(form if self._rest_form is None else self._rest_form,
                                       self.preconditioner)
            if refresh is not None:
                self.reuse = Reuse()

    @property
    def direct(self) -> bool:
        """Whether the route is the direct factorisation."""
        return self.kind == "direct"

    @property
    def krylov(self) -> bool:
        """Whether the next solve is by Krylov iterations (the iterative route, or the direct
        one preconditioned by an earlier matrix's factorisation), to which a tolerance applies."""
        return not self.direct or self._stale

    @property
    def forcing(self) -> float:
        """The largest relative Krylov tolerance of a Newton step (its forcing term's cap,
        Equilibrium.solve_tangent): 1e-2 for CG; tighter where the preconditioner was built
        from another matrix and the solve is not CG, an earlier factorisation
        (:data:`STALE_FORCING`) or GMRES with the tangent at rest (:data:`AT_REST_FORCING`),
        whose residual then measures the step's error less well."""
        if self.direct:
            return STALE_FORCING
        return AT_REST_FORCING if self._rest_form is not None and not self.symmetric else 1e-2

    def new_design(self):
        """The design changed: a preconditioner built at rest is built anew at the next
        :meth:`prepare`; one kept across designs now belongs to an earlier design."""
        self._rest_stale = True
        if self.reuse is not None:
            self.reuse.new_design()

    @property
    def rebuild_due(self) -> bool:
        """On the iterative route, whether the form's next matrix should be assembled by the
        form, so that its preconditioner is set up from it (always, unless it is kept across
        designs)."""
        return not self.direct and (self.reuse is None or self.reuse.due)

    def rebuilt(self):
        """The owner assembled the form's matrix by the form: its preconditioner is the
        current design's."""
        if self.reuse is not None:
            self.reuse.built()

    def _iterations_allowed(self, kept: bool) -> int:
        """A solve's most Krylov iterations: a kept preconditioner's cap, if it has one."""
        cap = self.reuse.cap if kept else None
        return MAX_ITERATIONS if cap is None else min(cap, MAX_ITERATIONS)

    @property
    def _kept(self) -> bool:
        return self.reuse is not None and self.reuse.kept

    def _rebuild(self):
        """A kept preconditioner reached its cap in a solve: set it up from the current
        matrix (the owner's ``refresh``)."""
        self._refresh()
        self.reuse.built(in_solve=True)

    def prepare(self, near: bool = False):
        """Make the solver ready for the form's current matrix (after each assembly): the
        direct route factorises it (the first time) or refactorises it numerically; the
        iterative route's preconditioner was updated by the assembly itself.  ``near``: the
        matrix is close to the one factorised last (the same pattern): the direct route
        keeps that factorisation as a preconditioner (:data:`STALE_RTOL`), factorising only
        where it does not do."""
        if self.direct and near and self._inv is not None \
                and self._factorised is self.form.mat and not distributed(self.form.space.mesh):
            self._stale = True
            return
        self._stale = False
        if self._rest_form is not None and self._rest_stale:
            rest = self.form.mat.CreateColVector()
            rest[:] = 0.0
            self._rest_form.AssembleLinearization(rest)  # BDDC is set up by the assembly
            self._rest_stale = False
            self.rest_builds += 1
        if self.direct:
            # on a distributed mesh the direct route is NGSolve's MasterInverse (the matrix
            # gathered on rank 0), which has no numeric update: it is made anew
            # a new matrix (a form whose couplings change, e.g. contact pairs, is assembled
            # into a new sparsity pattern) is factorised anew too
            if self._inv is None or distributed(self.form.space.mesh) \
                    or self._factorised is not self.form.mat:
                self._inv = self.form.mat.Inverse(self.freedofs, inverse=self.inverse)
                self._factorised = self.form.mat
            else:
                self._inv.Update()

    def solve(self, rhs, out, *, rtol: float | None = None, transpose: bool = False,
              strict: bool = True, residual: float | None = None):
        """``out = A⁻¹ rhs`` (``A⁻ᵀ rhs`` with ``transpose``) on the free dofs, 0 on the
        others.  ``rtol``: the Krylov tolerance relative to the (preconditioned) norm of
        ``rhs`` (default :attr:`rtol`); ``strict``: raise :class:`SolverFailure` when it is
        not reached (Newton, which checks its residual itself, passes False).  ``residual``
        (CG on a form that is not condensed): instead of ``rtol``, stop once the Euclidean
        norm of the residual ``rhs - A out`` on the free dofs is at most this, the norm of
        Newton's convergence test (:meth:`_cg_to_residual`)."""
        self.solves += 1
        if residual is not None and not self.direct and self.symmetric \
                and not self.form.condense:
            self._cg_to_residual(rhs, out, float(residual), strict)
            return
        if not self.form.condense:
            self._solve(rhs, out, rtol, transpose, strict)
            return
        # a statically condensed form (local dofs, e.g. the mixed formulation's element fields):
        # A = [[A_cc, A_cl], [A_lc, A_ll]], its matrix the Schur complement S on the coupling
        # dofs; x_c = S⁻¹ (b_c - A_cl A_ll⁻¹ b_l), x_l = A_ll⁻¹ (b_l - A_lc x_c), and for Aᵀ
        # the same with every block transposed
        a = self.form
        ext, ext_trans, inner = a.harmonic_extension, a.harmonic_extension_trans, a.inner_solve
        if transpose and not self.symmetric:
            ext, ext_trans, inner = ext_trans.T, ext.T, inner.T
        if self._condensed_rhs is None:  # one work vector, kept for every solve
            self._condensed_rhs = rhs.CreateVector()
        r = self._condensed_rhs
        r.data = rhs
        r.data += ext_trans * rhs
        self._solve(r, out, rtol, transpose, strict)
        out.data += ext * out
        out.data += inner * rhs

    def _solve(self, rhs, out, rtol, transpose, strict):
        inverse = lambda: self._inv.T if transpose and not self.symmetric else self._inv
        if self.direct and not self._stale:
            out.data = inverse() * rhs
            return
        if self.freedofs is not None:
            free = rhs.CreateVector()
            self._on_free_dofs(rhs, free)
            rhs = free
        if self.direct:  # preconditioned by the factorisation of an earlier matrix
            self.stale_solves += 1
            tol = STALE_RTOL if rtol is None else max(float(rtol), STALE_RTOL)
            krylov = self._krylov(inverse(), rhs, out, tol, STALE_ITERATIONS, transpose)
            res = krylov.residuals
            if not (res and (res[0] == 0 or res[-1] <= tol * res[0])):
                self.stale_failed += 1
                self.prepare()  # too far from the factorised matrix: factorise this one
                out.data = inverse() * rhs
            return
        tol = self.rtol if rtol is None else float(rtol)
        kept = self._kept
        krylov = self._krylov(self._pre.mat, rhs, out, tol,
                              self._iterations_allowed(kept), transpose)
        res = krylov.residuals
        if kept and res and not (res[0] == 0 or res[-1] <= tol * res[0]):
            self._rebuild()  # and solve again with the current design's preconditioner
            krylov = self._krylov(self._pre.mat, rhs, out, tol, MAX_ITERATIONS, transpose)
            res = krylov.residuals
        mat = self.form.mat.T if transpose and not self.symmetric else self.form.mat
        if strict and res and res[0] > 0 and not res[-1] <= tol * res[0]:
            # GMRES ends at a breakdown of its Arnoldi process without recording the residual
            # it reached (BDDC whose coarse space holds every dof is an exact inverse: one
            # iteration, the solution exact); measure that residual as GMRES does
            r = rhs.CreateVector()
            r.data = rhs - mat * out
            pr = rhs.CreateVector()
            pr.data = self._pre.mat * r
            reached = float(pr.Norm()) / res[0]
            if not reached <= tol:
                raise SolverFailure(f"{krylov.name} with {self.preconditioner} did "
                                    f"not reach the relative tolerance {tol:.1e} in "
                                    f"{krylov.iterations} iterations (reached {reached:.1e})")

    def _krylov(self, pre, rhs, out, tol: float, maxiter: int, transpose: bool):
        """CG (GMRES, restarted, for an unsymmetric matrix) on the form's matrix (transposed
        with ``transpose``) preconditioned by ``pre``, from 0 (``rhs`` zero on the fixed
        dofs); its iterations counted.  Returns a :class:`~.krylov.KrylovRun`."""
        mat = self.form.mat.T if transpose and not self.symmetric else self.form.mat
        if self.symmetric:
            run = cg(mat, pre, rhs, out, tol, maxiter)
        else:
            run = gmres(mat, pre, rhs, out, tol, maxiter, GMRES_RESTART)
        self._count(run.iterations)
        return run

    def _count(self, iterations: int):
        self.iterations = iterations
        self.total_iterations += iterations
        if self.reuse is not None:
            self.reuse.count(iterations)

    def _cg_to_residual(self, rhs, out, target, strict):
        """CG to the Euclidean residual ``target`` on the free dofs
        (:func:`.krylov.cg_to_residual`, on a copy of ``rhs``)."""
        r = rhs.CreateVector()
        self._on_free_dofs(rhs, r)
        kept = self._kept
        run = cg_to_residual(self.form.mat, self._pre.mat, r, out, target, self._free_mask(),
                             self._iterations_allowed(kept))
        self._count(run.iterations)
        if kept and not run.residuals[-1] <= target:
            # the kept preconditioner reached its cap: rebuilt, CG goes on from ``out``, whose
            # residual ``r`` holds
            self._rebuild()
            step = out.CreateVector()
            more = cg_to_residual(self.form.mat, self._pre.mat, r, step, target,
                                  self._free_mask(), MAX_ITERATIONS)
            self._count(more.iterations)
            out.data += step
            run = KrylovRun(run.name, run.iterations + more.iterations,
                            [run.residuals[0], more.residuals[-1]])
        if strict and not run.residuals[-1] <= target:
            raise SolverFailure(f"CG with {self.preconditioner} did not reach the residual "
                                f"{target:.1e} in {run.iterations} iterations (reached "
                                f"{run.residuals[-1]:.1e})")

    def _on_free_dofs(self, rhs, into):
        """``into = rhs`` on the free dofs, 0 on the others: the fixed dofs' entries of a
        right-hand side (an adjoint's dJ/du) are no equation of the free dofs' system (GMRES
        counted them in its residual, which then stagnated at 1; measured: a follower adjoint
        on pneunet-3d)."""
        from ngsolve import Projector

        if self.freedofs is None:
            into.data = rhs
        else:
            into.data = Projector(self.freedofs, True) * rhs

    def _free_mask(self) -> np.ndarray:
        if self._free is None:
            self._free = (np.ones(self.form.space.ndof, dtype=bool) if self.freedofs is None
                          else np.array(list(self.freedofs), dtype=bool))
        return self._free

    @property
    def info(self) -> dict:
        """The route, for the run summary: ``kind`` (direct | iterative), ``setting`` (what
        was asked: auto | direct | iterative), ``method`` (the direct solver, or CG / GMRES),
        ``preconditioner`` (None for direct), ``tolerance`` (the default Krylov tolerance,
        None for direct), ``iterations`` (Krylov iterations of the last solve),
        ``total_iterations`` and ``solves``; on the direct route ``factors_reused``, the
        solves preconditioned by an earlier matrix's factorisation (Newton's tangent for the
        adjoint's), and ``factors_reused_failed``, those of them that factorised after all;
        ``preconditioner_builds``: how often a preconditioner built at rest, or kept across
        designs, was built; of the latter ``preconditioner_kept_designs``, the designs it
        served that it was not built at, and ``preconditioner_rebuilt_in_solve``, the solves
        that rebuilt it at their cap."""
        iterative = not self.direct
        return {"kind": self.kind, "setting": self.setting,
                "method": (("CG" if self.symmetric else "GMRES")
                           if iterative else self.inverse),
                "preconditioner": (f"{self.preconditioner} at rest, once per design"
                                   if self._rest_form is not None else self.preconditioner),
                "tolerance": self.rtol if iterative else None,
                "iterations": self.iterations, "total_iterations": self.total_iterations,
                "solves": self.solves, "ndof": self.form.space.ndof,
                "factors_reused": self.stale_solves, "factors_reused_failed": self.stale_failed,
                "preconditioner_builds": self.rest_builds + (self.reuse.builds if self.reuse
                                                             is not None else 0),
                "preconditioner_kept_designs": self.reuse.kept_designs if self.reuse else 0,
                "preconditioner_rebuilt_in_solve": (self.reuse.rebuilt_in_solve if self.reuse
                                                    else 0)}
