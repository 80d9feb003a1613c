"""Solving the mechanics block for equilibrium: the problem
:func:`~pacto_ng.physics.newton.solve_with_continuation` drives (residual, tangent, its
factorisation and solves, the admissibility guard, the norm of the external load), the warm
start and the forward pass.

:class:`Equilibrium` is a part of :class:`~pacto_ng.physics.mechanics.Mechanics` (its methods
act on the block's forms and routes); :class:`NewtonFailure` is what a forward pass raises when
no equilibrium is reached.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from ngsolve import GridFunction

from ..parallel import everywhere, free_norm
from .contact import PairsUnsettled, settle
from .design_path import field_values, follow
from .materials import jacobian
from .newton import NewtonResult, solve_with_continuation
from .quadrature import element_points, guard_rules
from .solvers import LinearSolver, adjoint_rtol

#: with contact, a warm start gives up after this many Newton iterations without a new
#: smallest residual (a load ramp from zero then takes over; a load ramp's steps may take up
#: to ``max_iter`` without one): the slotted slab of benchmarks/contact.py at 3 kPa after
#: 1 kPa, every wall a candidate, took 55 Newton iterations with a warm start of 30, 37 so
#: (2026-12-07)
WARM_STALL = 8


class NewtonFailure(RuntimeError):
    """Raised by a forward pass whose equilibrium could not be reached."""

    def __init__(self, result: NewtonResult):
        super().__init__(f"Newton failed: reached load factor {result.load_reached:.4g} of 1 "
                         f"({result.reason})")
        self.result = result


@dataclass(frozen=True)
class WarmState:
    """Where the next forward pass starts (:attr:`Equilibrium.state`; a run checkpoints it).

    ``u``: the displacement dofs; ``converged``: ``u`` is an equilibrium (the next pass starts
    from it, else it ramps the load from zero); ``ramp_first``: Newton's first load increment
    (a fraction) of the last successful ramp from zero, where the next ramp starts (None: no
    ramp yet, the settings' first increment)."""

    u: np.ndarray
    converged: bool
    ramp_first: float | None = None


class Equilibrium:
    """The equilibrium part of :class:`~pacto_ng.physics.mechanics.Mechanics` (see the module).

    The load norm's route (:attr:`load_norm_route`): with only design-independent loads the
    load vector is fixed and its norm is computed once; for a linear system it is the norm of
    ``f``; for a design-dependent load on a stress-free energy (``∂φ/∂G = 0`` at ``G = 0``,
    declared) ``R(0) = -s f``, so it is the norm of ``f`` = (point/edge loads) + (body load),
    with no ``Apply`` of the energy at ``u = 0``; otherwise the residual at ``u = 0``.
    """

    def _start_equilibrium(self, guard, *, coarse, fixed_loads: bool, load_vectors: bool):
        """The state of this part, once the block's forms are built: ``coarse`` (the regions
        of the tangent's boundary terms, :class:`~pacto_ng.physics.solvers.LinearSolver`),
        ``fixed_loads`` (only design-independent loads) and ``load_vectors`` (the load norm
        from the load vectors) choose the load norm's route."""
        from ngsolve import VOL, GridFunction, Grad, LinearForm

        # the tangent's solver (solvers.py), its preconditioner registered before the first
        # assembly (a linear K's kept across designs: LinearSystem.assemble, reuse.py)
        form, lin = (self._lin.a, self._lin) if self._lin is not None else (self.a, None)
        self._solver = LinearSolver(
            form, self.space.FreeDofs(form.condense), setting=self.settings.solver,
            symmetric=self.symmetric, order=self.order, inverse=self.inverse_type,
            coarse=coarse, at_rest=self._tangent_form, refresh=lin and lin.assemble_form)
        if lin is not None:
            lin.solver = self._solver
        self.settings = self.settings.for_route(self._solver.direct)  # Newton's tolerance
        self._solver.rtol = adjoint_rtol(self.settings.rtol)  # its default: the adjoint's
        self._tangent_at = None  # id of the state the factorisation belongs to
        self.result: NewtonResult | None = None
        self._ramp_first = None  # first increment of the last successful ramp from zero
        self._at_load = 0.0  # the load factor of the equilibrium the state holds (0: unknown)
        self._design = None  # the field values of that equilibrium (None: unknown)
        #: called with (load factor, state) at every equilibrium Newton's load ramp reaches
        #: (a progress line), or None
        self.on_step = None
        self._gtrial = GridFunction(self.space)
        guard_cf = None
        if self.mixed is not None:  # J > 0, Θ > 0 and the model's guard at F̄ (mixed.py)
            u, theta, _ = self.mixed.split(self._gtrial)
            guard_cf = self.mixed.guard(self._energy, guard, Grad(u), theta, self.coeffs)
        elif guard is not None:
            guard_cf = guard(Grad(self._gtrial), self.coeffs)
        self._guard = guard_cf
        if guard_cf is not None:
            self._guard_cf = guard_cf.Compile()
            self._guard_pts = self.mesh.MapToAllElements(
                guard_rules(self.rules, self._traits.guard_points), VOL)
        self._rhs = self.gfx.vec.CreateVector()
        self._ext = self.gfx.vec.CreateVector()
        self.contact = None  # a SelfContact (use_contact)
        # with only design-independent loads the load vector is fixed: its norm is computed once
        self._fixed_loads = fixed_loads
        self._unit_load_norm = None
        self._f_unit = None  # the unit external load vector (the self-adjoint shortcut's)
        # the point loads are design independent: assembled here, once; the body load is the
        # residual's own LinearForm (_fbody)
        self._load_form = None
        if load_vectors:
            v = self.displacement(self.space.TestFunction())
            self._load_form = LinearForm(self.space)
            for ld in self.loads:
                self._load_form += ld.work(self.mesh, v)
            self._load_form.Assemble()

    def use_contact(self, contact) -> None:
        """Add the self-contact ``contact`` (:class:`~pacto_ng.physics.contact.SelfContact` on
        this block's displacement space) to the equilibrium, paired at the current state; the
        pairs stay until the caller updates them (:meth:`pairs_mismatch`).  A block on the
        linear route (a fixed K) takes no contact: ValueError."""
        if self._lin is not None:
            raise ValueError("contact needs the nonlinear route (build the block with "
                             "linear=False)")
        self.contact = contact
        self.settings = replace(self.settings.for_contact(), warm_stall=WARM_STALL)
        contact.update(self.a, self.gfx.vec)

    def forward_paired(self, *values) -> int:
        """:meth:`forward`, and with contact paired anew at each equilibrium and solved again
        until the pairs hold (:func:`~pacto_ng.physics.contact.settle`); the Newton
        iterations over all the solves.  NewtonFailure (its iterations those of all the
        solves) where a solve fails or the pairs do not settle."""
        done = 0

        def solve() -> int:
            nonlocal done
            try:
                self.forward(*values)
            except NewtonFailure as failure:
                res = failure.result
                raise NewtonFailure(replace(res, iterations=done + res.iterations)) from None
            done += self.result.iterations
            return self.result.iterations

        if self.contact is None:
            return solve()
        try:
            return settle(solve, self.pairs_mismatch, self.settings.rtol)
        except PairsUnsettled as err:
            raise NewtonFailure(replace(self.result, converged=False, iterations=done,
                                        reason=str(err))) from None

    def pairs_mismatch(self, vec=None, load=None) -> float:
        """Pair the contact surface anew at the equilibrium ``vec`` (default: the block's) at
        load factor ``load`` (default: the target); the residual there with the new pairs,
        relative to the load (within Newton's tolerance: the pairs hold; at no load, the
        residual itself)."""
        vec = self.gfx.vec if vec is None else vec
        load = self.target if load is None else load
        self.contact.update(self.a, vec)
        r = vec.CreateVector()
        self.residual(vec, r, load)
        ref = self.load_norm(load)
        return free_norm(r, self.free) / (ref if ref > 0 else 1.0)  # at no load: absolute

    def _paired_step(self, load, vec) -> None:
        """``on_step`` with contact: the pairs follow a load ramp, paired anew at each of its
        equilibria (walls that slide along each other: a Neo-Hookean slotted block loaded on
        its top face to 10 kPa settled in 183 Newton iterations so, 378 without, 2026-12-07)."""
        self.contact.update(self.a, vec)
        if self.on_step is not None:
            self.on_step(load, vec)

    # -- the problem interface used by Newton --------------------------------------------------
    def residual(self, vec, out, load):
        self.load.Set(load)
        if self._lin is not None:
            self._lin.residual(vec, out, load)
            return
        self.a.Apply(vec, out)
        if self._fbody is not None:
            out.data -= load * self._body_load()

    def predictor_residual(self, vec, out, load):
        """``K u - s f`` with the assembled ``K`` (linear systems; one sparse product): Newton's
        first residual, from which the correction is computed.  Its round-off (products with
        K cancel where the structure moves rigidly) is corrected by the next iteration, whose
        convergence test uses :meth:`residual` (element by element)."""
        if self._lin is None:
            self.residual(vec, out, load)
            return
        self.load.Set(load)
        self._lin.assemble()
        out.data = self._lin.a.mat * vec
        out.data -= load * self._lin.f.vec

    def _body_load(self):
        """The body-load vector ``t ∫ b·v dΩ`` of the current fields (assembled once per design)."""
        if self._coupling is not None:
            if self._fbody_stale:
                self._coupling.load()
                self._fbody_stale = False
            return self._coupling.vec
        if self._fbody_stale:
            self._fbody.Assemble()
            self._fbody_stale = False
        return self._fbody.vec

    @property
    def matrix(self):
        """The tangent matrix last assembled by :meth:`assemble_tangent`."""
        return self._lin.a.mat if self._lin is not None else self.a.mat

    def assemble_tangent(self, vec, load, near: bool = False):
        """The tangent at ``vec`` and ``load``, ready to solve with; ``near``: close to the one
        factorised last, whose factorisation may precondition it (LinearSolver.prepare)."""
        self.load.Set(load)
        if self._lin is not None:
            if self._tangent_at is not None:
                return  # u- and load-independent: this design's matrix is factorised already
            self._lin.assemble()
        else:
            self.a.AssembleLinearization(vec)
        self._solver.prepare(near)
        self._tangent_at = (load, vec.FV().NumPy().copy()) if not self.linear else ("linear",)

    def solve_tangent(self, rhs, out):
        """``out = K⁻¹ rhs``.  A linear problem's Krylov solve stops once the residual's norm
        on the free dofs is half what Newton's convergence test asks (``rtol |f|``, ``|f|``
        the load norm): one solve per design.  A nonlinear problem's (the iterative route's,
        or a sweep's preconditioned by an earlier factorisation) stops at the relative
        tolerance ``max(0.1 rtol |f| / |rhs|, min(c, |rhs| / |f|))`` of the preconditioned
        norm (``|rhs|`` the residual's; ``c`` the solver's
        :attr:`~.solvers.LinearSolver.forcing`): never tighter than a tenth of what Newton's
        convergence test asks, and loose far from equilibrium (an inexact Newton step whose
        forcing term shrinks with the residual)."""
        rtol = residual = None
        if self._solver.krylov:
            ref = self.load_norm(self.target)
            if self.linear:
                residual = 0.5 * self.settings.rtol * ref
            else:
                res = free_norm(rhs, self.free)
                if res > 0 and ref > 0:
                    cap = self._solver.forcing
                    rtol = max(0.1 * self.settings.rtol * ref / res, min(cap, res / ref))
        self._solver.solve(rhs, out, rtol=rtol, residual=residual, strict=False)

    @property
    def solver_info(self) -> dict:
        """The tangent's linear solver, for the run summary
        (:attr:`~pacto_ng.physics.solvers.LinearSolver.info`: kind, method, preconditioner,
        tolerance (the adjoint's Krylov tolerance), Krylov iterations), with Newton's residual
        tolerance ``newton_rtol`` (relative to the load; the route's unless set)."""
        return dict(self._solver.info, newton_rtol=self.settings.rtol)

    def admissible(self, vec) -> bool:
        if self._guard is None:
            return everywhere(self.mesh, np.all(np.isfinite(vec.FV().NumPy())))
        self._gtrial.vec.data = vec
        vals = self._guard_cf(self._guard_pts)
        return everywhere(self.mesh, np.all(np.isfinite(vals)) and np.all(vals > 0.0))

    def lowest_jacobian(self, points: str = "quadrature") -> dict:
        """Where ``det F`` (``F = I + ∇u`` of the current displacement; in 2D of the in-plane
        deformation) is lowest: ``{"J", "element", "point"}`` with the element's index
        (NGSolve's order) and the kind of point (``"quadrature point"``, ``"vertex"``, ``"edge
        midpoint"`` or ``"centroid"``).  ``points``: ``"quadrature"`` (the points of the forms'
        rule) or ``"corners"`` (vertices, edge midpoints and centroid only).  Any element type
        of :mod:`~pacto_ng.physics.quadrature`: triangles, quadrilaterals, tetrahedra,
        hexahedra."""
        from ngsolve import VOL, Grad

        if points not in ("quadrature", "corners"):
            raise ValueError(f"points must be 'quadrature' or 'corners' (got '{points}')")
        rules = guard_rules(self.rules, "element")
        vals = np.asarray(jacobian(Grad(self.gfu))(self.mesh.MapToAllElements(rules, VOL))).ravel()
        best = (np.inf, -1, "")
        start = 0
        for el in self.mesh.Elements(VOL):
            n_quad = len(self.rules[el.type].points)
            kinds = ["quadrature point"] * n_quad + element_points(el.type.name)[1]
            own = vals[start:start + len(kinds)]
            start += len(kinds)
            sel = slice(0, n_quad) if points == "quadrature" else slice(n_quad, None)
            j = int(np.argmin(own[sel])) + (0 if points == "quadrature" else n_quad)
            if own[j] < best[0]:
                best = (float(own[j]), el.nr, kinds[j])
        return {"J": best[0], "element": best[1], "point": best[2]}

    def load_norm(self, load):
        """Norm of the external load vector (the residual at u = 0) at load factor ``load``."""
        if self._fixed_loads and self._unit_load_norm is not None:
            return abs(load) * self._unit_load_norm
        if self._lin is not None and not self._fixed_loads:
            # R(0) = -s f: the norm of the (design-dependent) load vector, no residual needed
            return abs(load) * self._lin.load_norm()
        if self._load_form is not None:
            f = self._load_form.vec.CreateVector()
            f.data = self._load_form.vec + self._body_load()
            return abs(load) * free_norm(f, self.free)
        if self._fixed_loads:
            self._ext[:] = 0.0
            self.residual(self._ext, self._rhs, 1.0)
            self._unit_load_norm = free_norm(self._rhs, self.free)
            # the unit external load vector f (R(0) = -f), kept for the self-adjoint shortcut
            self._f_unit = self._rhs.FV().NumPy().copy()
            self._f_unit[~self.free] = 0.0
            self._f_unit *= -1.0
            return abs(load) * self._unit_load_norm
        self._ext[:] = 0.0
        self.residual(self._ext, self._rhs, load)
        return free_norm(self._rhs, self.free)

    @property
    def load_norm_route(self) -> str:
        """How :meth:`load_norm` is computed: ``"fixed"``, ``"linear_system"``,
        ``"load_vectors"`` or ``"residual"`` (see the class)."""
        if self._fixed_loads:
            return "fixed"
        if self._lin is not None:
            return "linear_system"
        if self._load_form is not None:
            return "load_vectors"
        return "residual"

    def load_changed(self):
        """Say that the loads changed outside the load factor (e.g. a pressure Parameter inside
        a load): the unit load vector and its norm, kept for design-independent loads, are
        recomputed at the next use."""
        self._unit_load_norm = None
        self._f_unit = None
        self._at_load = 0.0  # the state is no equilibrium of the new loads
        self._design = None

    # -- the fields it gives ----------------------------------------------------------------
    @property
    def u(self):
        """The displacement, a GridFunction (of the mixed state too): the block's output, for
        evaluating, differentiating (``Grad(mech.u)``) and copying; the block sets it."""
        return self.gfu

    @property
    def state_vector(self):
        """The state's coefficient vector (``u``, or ``(u, ϑ, p̃)`` mixed), in place: a path
        follower or a sweep that moves the equilibrium writes it."""
        return self.gfx.vec

    @property
    def displacement_dofs(self) -> slice:
        """The displacement's entries of :attr:`state_vector` (all of it, or the first
        component of the mixed state's)."""
        return slice(0, self.fes.ndof)

    @property
    def ndof(self) -> int:
        """The number of displacement dofs (over every rank of a distributed mesh)."""
        return int(self.fes.ndofglobal)

    def displacement_from(self, values):
        """A new displacement GridFunction holding ``values`` (the dofs of :attr:`u`)."""
        gf = GridFunction(self.fes)
        gf.vec.FV().NumPy()[:] = values
        return gf

    # -- the warm state ---------------------------------------------------------------------
    @property
    def state(self) -> WarmState:
        """The warm state (a copy): where the next forward pass starts."""
        return WarmState(self.gfx.vec.FV().NumPy().copy(),
                         bool(self.result is not None and self.result.converged),
                         self._ramp_first)

    def set_state(self, state: WarmState, *, result: NewtonResult | None = None):
        """Start the next forward pass from ``state`` (e.g. :attr:`state` of earlier, or of a
        checkpoint).  ``result`` (a :class:`NewtonResult`) replaces the default record of the
        state: converged at the full load, or none."""
        self.gfx.vec.FV().NumPy()[:] = state.u
        self._ramp_first = state.ramp_first
        if result is not None:
            self.result = result
        else:
            self.result = NewtonResult(True, load_reached=1.0) if state.converged else None
        self._at_load = self.result.load_reached if self.result is not None else 0.0
        self._design = None  # the design of that state is not known

    # -- block interface ------------------------------------------------------------------------
    def set_fields(self, *values):
        for f, v in zip(self.fields, values):
            if isinstance(v, np.ndarray):
                # densities live in [0, 1]; round-off below 0 (or -0.0) would make ρ^p NaN
                f.gf.vec.FV().NumPy()[:] = np.where(v > 0.0, v, 0.0)
            else:
                f.gf.vec.data = v
        self._tangent_at = None  # a new design: any factorisation is stale
        self._solver.new_design()  # ... and a preconditioner built at rest
        self._fbody_stale = True  # ... and so is the body load (it depends on the fields)
        if self._lin is not None:
            self._lin.stale = True

    def forward(self, *values):
        old = self._design
        self.set_fields(*values)
        # the design of the equilibrium about to be found: a nonlinear model without contact
        # (a part's analysis, whose design stays) may follow the design path from it next time
        new = None if self.linear or self.contact is not None else field_values(self.fields)
        # warm start from the last equilibrium (also one a failed solve reached on its way)
        warm = self.result is not None and (self.result.converged or self.result.load_reached > 0)
        if self.linear:
            warm = True  # one Newton step from any state solves a linear problem
        # a new design: a failed warm start follows the design path
        path = (warm and old is not None and new is not None
                and not everywhere(self.mesh, all(map(np.array_equal, old, new))))
        res = solve_with_continuation(
            self, self.gfx.vec, self.target, self.settings, warm=warm, linear=self.linear,
            first_increment=self._ramp_first, start=self._at_load, ramp=not path,
            on_step=self.on_step if self.contact is None else self._paired_step)
        if path and not res.converged:
            res = self._along_path(old, (new, values), res.iterations)
        self._at_load = res.load_reached
        self._design = new if res.converged else None
        if res.ramp_first is not None:
            self._ramp_first = res.ramp_first  # where the next ramp from zero starts
        self.result = res
        if not res.converged:
            raise NewtonFailure(res)
        out = self.gfx.vec.CreateVector()
        out.data = self.gfx.vec
        self._adjoint_ready = False
        return out

    def _along_path(self, old: list, new: tuple, tried: int) -> NewtonResult:
        """The equilibrium of the new design (``new``: its fields' copies and the values given,
        :func:`~pacto_ng.physics.design_path.follow`) along the design path from the state's
        (``old``), where a warm start of ``tried`` Newton iterations failed; where the path
        fails too, the load ramped from zero."""
        res = follow(self, self.gfx.vec, old, new, (self._at_load, self.target), self.settings)
        res.iterations += tried
        if not res.converged:
            more = solve_with_continuation(
                self, self.gfx.vec, self.target, self.settings, warm=False,
                first_increment=self._ramp_first, on_step=self.on_step)
            more.iterations += res.iterations
            res = more
        return res
