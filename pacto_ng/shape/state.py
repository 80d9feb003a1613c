"""A part's equilibrium on its current shape: the state that the shape gradient
(:mod:`~pacto_ng.shape.gradient`) differentiates.

On the current shape Ω of the part (:class:`~pacto_ng.shape.deformation.ShapeSpace` moves the
mesh) the state ``x`` solves, for every test function ``y``,

    R(x; y) = t ∫_Ω Dψ(x)[y] dx + t ∫_Γp P a(u) · v ds = 0,

``u`` and ``v`` the displacements of ``x`` and ``y``, with the stored energy density ``ψ`` of
the run's model (:func:`~pacto_ng.physics.energy.make_energy` of the run's
:class:`~pacto_ng.params.Parameters` on solid material everywhere,
:func:`~pacto_ng.post.part_analysis.solid_fields`, as
:class:`~pacto_ng.post.part_analysis.PartAnalysis` builds it), the thickness ``t`` of a 2D
part (1 in 3D), the wall pressure ``P`` on ``Γp`` with ``N`` the solid's outward normal
(:func:`~pacto_ng.physics.walls.outward_normal`) and

* ``fixed``: ``a(u) = N`` (the potential ``t ∫ P N · u ds``: a symmetric tangent);
* ``follower``: ``a(u) = cof(F̃) N``, ``F̃ = I + ∇_Γ u`` (``Grad(u).Trace()``; Nanson's
  formula ``n da = cof(F) N dA``, exact with the surface gradient: Bonet and Wood 2008,
  *Nonlinear continuum mechanics for finite element analysis*, 2nd ed., §4.2.5; the terms of
  :func:`~pacto_ng.physics.walls.follower_terms`): an unsymmetric tangent.

The formulation is the part analysis's (:func:`~pacto_ng.physics.mixed.formulation_for`):

* ``displacement``: ``x = u`` in ``U`` (VectorH1 of order ``p``, zero where ``supports`` fix
  it) and ``ψ(x) = φ(∇u)``;
* ``mixed`` (near-incompressible solids): ``x = (u, ϑ, p̃)`` with the element dilatation and
  pressure of :mod:`~pacto_ng.physics.mixed` and ``ψ(x) = φ(F̄ - I) + p̃ (J - Θ)``.  Its
  tangent is symmetric and indefinite: it is factorised whole (UMFPACK), the element fields
  not condensed.

Newton's method with load continuation and the guard of the formulation
(:func:`~pacto_ng.physics.newton.solve_with_continuation`) solves it, warm-started from the
last shape's state; the tangent ``K = ∂R/∂x`` comes from ``AssembleLinearization`` and is
factorised once and refactorised numerically (``Update``) with the same ordering afterwards.

Output springs.  One at a named point adds its energy ``k/2 (d̂ · u)²`` to ``R``, and so does one
spread about the point (:class:`~pacto_ng.physics.loads.Spring`), whose support the shape
holds (:class:`~pacto_ng.shape.deformation.ShapeSpace`'s ``near``).  One on a
boundary port is the runs' distributed spring of the same total stiffness,
``k/2 (1/|Γ|) ∫_Γ (d̂ · u)² ds`` (:class:`~pacto_ng.physics.loads.Spring`), with ``1/|Γ|`` of
the current shape.

The stored strain energy ``SE = t ∫_Ω ψ(x) dx`` (the potential of the residual's first term,
``½ u · K u`` for the linear model; in the mixed formulation ``∫ p̃ (J - Θ) = 0`` at
equilibrium, ``p̃`` being one of its own test functions), summed by the quadrature of the
assembled forms, which ``DiffShape`` uses too (``Integrate`` takes another: 1e-6 apart on a
curved 2D mesh).
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np
from ngsolve import (L2, VOL, BilinearForm, CF, Cof, Det, Grad, GridFunction, Id,
                     InnerProduct, Integrate, Parameter, Variation)

from ..errors import InputError
from ..parallel import free_norm
from ..physics.energy import make_energy
from ..physics.contact import PairsUnsettled, settle
from ..physics.equilibrium import NewtonFailure
from ..physics.mixed import formulation_for, has_simplices, stored_energy
from ..physics.newton import solve_with_continuation
from ..physics.quadrature import integration_rules, mechanics_rules
from ..physics.spaces import block_spaces
from ..physics.walls import outward_normal
from ..post.part_analysis import solid_fields
from .contact_term import ShapeContact
from .deformation import ShapeSpace, shape_ds, shape_dx

KINDS = ("fixed", "follower")


class PartState:
    """The equilibrium of a part on its current shape (see the module).

    Parameters
    ----------
    mesh : ngsolve.Mesh
        The part (2D: plane strain or stress and thickness from ``params``; 3D).  Its current
        deformation (``SetDeformation``) is the shape every :meth:`solve` sees.
    params : pacto_ng.params.Parameters
        The run's parameters: model (not ``auto``), E1, ν, plane, thickness, material,
        formulation, Newton's settings, order.
    supports : Supports
        Dirichlet conditions of the displacement by region name.
    ports : tuple of Port
        The output ports (their springs are part of the state).
    pressure : float
        The wall pressure ``P`` (negative: suction).
    kind : {"fixed", "follower"}
        The pressure's load.
    boundary : str
        The wetted wall ``Γp``.
    order : int, optional
        Displacement order (default ``params.order``, else 1).

    Attributes: ``state`` (the state's GridFunction), ``u`` (its displacement: ``state``
    itself, or its first component), ``formulation``, ``result`` (the last solve's
    :class:`~pacto_ng.physics.newton.NewtonResult`), ``free`` (numpy mask of the state's free
    dofs), ``thickness``, ``kind``, ``contact``.
    """

    def __init__(self, mesh, *, params, supports, ports, pressure: float,
                 kind: str = "fixed", boundary: str = "pressure", order: int | None = None):
        if kind not in KINDS:
            raise ValueError(f"kind must be one of {', '.join(KINDS)}, not {kind!r}")
        if boundary not in mesh.GetBoundaries():
            raise ValueError(f"the part has no '{boundary}' boundary to apply the pressure on")
        if not math.isfinite(pressure):
            raise ValueError(f"pressure must be finite (got {pressure!r})")
        if params.model == "auto":
            raise InputError("model: auto is chosen by a run; give the model the run used")
        order = int(order or params.order or 1)
        self.formulation = formulation_for(
            params.formulation, model=params.model, nu=params.nu, plane=params.plane,
            dim=mesh.dim, order=order, simplices=has_simplices(mesh))
        kw, self.fes, self.mixed, self.states = block_spaces(mesh, order, supports,
                                                             self.formulation)
        self.mesh, self.kind, self.boundary, self.ports = mesh, kind, boundary, ports
        self.contact: ShapeContact | None = None
        self.thickness = float(params.thickness) if mesh.dim == 2 else 1.0
        # the mixed formulation's bubble (order + 1 on triangles) raises the forms' own
        # quadrature order above that of their shape derivative (FD 1.4e-5 to 3.2e-5 off,
        # tests/shape/test_mixed_gradient.py): one rule for both, the part analysis's
        self.dx = shape_dx() if self.mixed is None else shape_dx(
            mechanics_rules(order, bubble="orderinner" in kw))
        self.free = np.array(list(self.states.FreeDofs()), dtype=bool)
        values = solid_fields(mesh)
        l2 = L2(mesh, order=0)
        self.coeffs = {name: GridFunction(l2) for name in values}
        for name, vals in values.items():
            self.coeffs[name].vec.FV().NumPy()[:] = vals
        energy, guard, linear = make_energy(params, Parameter(params.penal), tuple(values))
        self.energy = energy
        self.linear = bool(linear) and kind == "fixed"
        self.normal = outward_normal(mesh, boundary)
        self.sign = math.copysign(1.0, pressure)
        self.pressure = abs(float(pressure))
        self.load = Parameter(self.pressure)  # the load factor of Newton's continuation
        self.settings = params.newton.settings()
        self.state, self.adjoint_state = GridFunction(self.states), GridFunction(self.states)
        self.parts, self.adjoint_parts = self.split(self.state), self.split(self.adjoint_state)
        self.u, self.lam = self.parts[0], self.adjoint_parts[0]
        self.a, self._se = self._tangent_form(self._symmetric()), self._energy_form()
        self._E1 = float(params.E1)
        self._inverse = None
        self._trial = GridFunction(self.states)
        self._guard = self._guard_of(guard, self.split(self._trial))
        self._points = mesh.MapToAllElements(integration_rules(2 * self.fes.globalorder), VOL)
        self.result = None
        self._started = False

    # -- the forms -----------------------------------------------------------------------------
    def split(self, x) -> tuple:
        """The components of a state ``x`` (a trial or test function or a GridFunction of the
        state's space): ``(u,)``, or ``(u, ϑ, p̃)`` in the mixed formulation."""
        return (x,) if self.mixed is None else self.mixed.split(x)

    def density(self, parts):
        """``ψ`` of a state's components ``parts`` (see the module), per unit volume."""
        return stored_energy(self.energy, self.mixed, parts, self.coeffs)

    def _guard_of(self, guard, parts):
        """The admissibility CF of the state ``parts`` (positive where admissible), or None."""
        if self.mixed is not None:
            return self.mixed.guard(self.energy, guard, Grad(parts[0]), parts[1], self.coeffs)
        return None if guard is None else guard(Grad(parts[0]), self.coeffs)

    def _symmetric(self) -> bool:
        """Whether the tangent is stored and factorised as symmetric positive definite."""
        return self.kind == "fixed" and self.mixed is None and self.contact is None

    def traction(self, u):
        """``a(u)``: ``N`` (fixed) or ``cof(I + ∇_Γ u) N`` (follower)."""
        if self.kind == "fixed":
            return self.normal
        return Cof(Id(self.mesh.dim) + Grad(u).Trace()) * self.normal

    def _tangent_form(self, symmetric: bool):
        """The residual ``R(x; y)`` as a BilinearForm (Variation of the potential, and the
        follower term as a residual term); ``symmetric``: its matrix in symmetric storage."""
        trial, test = self.states.TnT()
        parts = self.split(trial)
        u, v = parts[0], self.split(test)[0]
        t, P = self.thickness, self.sign * self.load
        a = BilinearForm(self.states, symmetric=symmetric)
        a += Variation((t * self.density(parts)).Compile() * self.dx)
        if self.kind == "fixed":
            a += Variation(t * P * InnerProduct(self.normal, u) * shape_ds(self.boundary))
        else:
            a += t * P * InnerProduct(self.traction(u), v) * shape_ds(self.boundary)
        self.boundary_springs = []
        for p in self.ports:  # output springs
            for spring in p.springs():
                if p.region not in self.mesh.GetBoundaries():
                    # at a named point, or spread about it over a support the shape holds
                    a += Variation(spring.energy(self.mesh, u))
                    continue
                # on a boundary: k/2 (1/|Γ|) ∫_Γ (d̂·u)² ds, 1/|Γ| of the current shape
                d = np.asarray(spring.direction, dtype=float)
                term = (CF(tuple(d / np.linalg.norm(d))), Parameter(1.0), spring)
                self.boundary_springs.append(term)
                a += Variation(0.5 * spring.stiffness * term[1] * InnerProduct(term[0], u) ** 2
                               * shape_ds(spring.region))
        return a

    def _measure_springs(self) -> None:
        """``w = 1/|Γ|`` of every boundary spring on the current shape."""
        for _, w, spring in self.boundary_springs:
            w.Set(1.0 / float(Integrate(CF(1.0) * shape_ds(spring.region), self.mesh)))

    def _energy_form(self):
        """``SE(x) = t ∫_Ω ψ(x) dx`` as a BilinearForm (the Variation of the residual's own):
        ``Energy`` gives ``SE``, ``Apply`` ``∂SE/∂x``, by the quadrature of the assembly (that
        of ``DiffShape``; ``Integrate`` takes another, and differs by ~1e-6 on a curved mesh)."""
        form = BilinearForm(self.states, symmetric=True)
        density = self.density(self.split(self.states.TrialFunction()))
        form += Variation((self.thickness * density).Compile() * self.dx)
        return form

    def use_contact(self, space: ShapeSpace, names) -> None:
        """The walls ``names`` in frictionless self-contact from now on, the shape's
        deformation that of ``space`` (:mod:`pacto_ng.shape.contact_term`): in the state, its
        tangent and adjoint, and the shape gradient."""
        self.contact = ShapeContact(self.states, space, names, E1=self._E1,
                                    thickness=self.thickness,
                                    displacement=lambda x: self.split(x)[0])
        self.a = self._tangent_form(False)  # full storage: the contact's tangent is added
        self.linear, self._inverse = False, None
        self.settings = self.settings.for_contact()

    # -- the problem Newton drives (pacto_ng.physics.newton) ---------------------------------
    def residual(self, vec, out, load):
        self.load.Set(load)
        self.a.Apply(vec, out)
        if self.contact is not None:
            self.contact.add_residual(vec, out)

    def assemble_tangent(self, vec, load):
        self.load.Set(load)
        self.a.AssembleLinearization(vec)
        if self.contact is not None:  # factorised anew where a pairing made a new pattern
            tangent = self.contact.tangent_with(self.a.mat, vec)
            if self.contact.new_pattern or self._inverse is None:
                self._inverse = tangent.Inverse(self.states.FreeDofs(), inverse="umfpack")
            else:
                self._inverse.Update()
        elif self._inverse is None:
            inverse = "sparsecholesky" if self._symmetric() else "umfpack"
            self._inverse = self.a.mat.Inverse(self.states.FreeDofs(), inverse=inverse)
        else:
            self._inverse.Update()  # the same sparsity: numeric refactorisation only

    def solve_tangent(self, rhs, out):
        out.data = self._inverse * rhs

    def solve_transposed(self, rhs, out):
        """``Kᵀ out = rhs`` with the last factorised tangent; with contact, the tangent at the
        state with the pairs' motion (:meth:`~.contact_term.ShapeContact.with_motion`),
        factorised for this solve."""
        if self.contact is not None:
            tangent = self.contact.with_motion(self.state.vec)
            inverse = tangent.Inverse(self.states.FreeDofs(), inverse="umfpack")
            out.data = inverse.T * rhs
            return
        out.data = (self._inverse if self._symmetric() else self._inverse.T) * rhs

    def admissible(self, vec) -> bool:
        if self._guard is None:
            return bool(np.all(np.isfinite(vec.FV().NumPy())))
        self._trial.vec.data = vec
        vals = np.asarray(self._guard(self._points))
        return bool(np.all(np.isfinite(vals)) and np.all(vals > 0.0))

    def load_norm(self, load):
        """``|R(0)|`` on the free dofs at load factor ``load``: the external load."""
        zero, out = self.state.vec.CreateVector(), self.state.vec.CreateVector()
        zero[:] = 0.0
        self.residual(zero, out, load)
        return free_norm(out, self.free)

    # -- the equilibrium -------------------------------------------------------------------------
    def equilibrium(self, ramp: bool = True) -> None:
        """Equilibrium on the current shape (warm-started from the last one's); NewtonFailure
        if Newton does not reach the pressure (with ``ramp`` False, if the warm start fails:
        no ramp from zero).  With contact: Newton with the pairs fixed, then paired anew,
        until they hold to Newton's tolerance (:func:`~pacto_ng.physics.contact.settle`),
        each solve after the first from the last pairing's equilibrium (no ramp from zero); a
        load ramp pairs anew at each of its steps."""
        self._measure_springs()
        solves = 0

        def solve() -> int:
            nonlocal solves
            warm = self.result is not None or self._started
            self.result = solve_with_continuation(
                self, self.state.vec, self.pressure, self.settings, warm=warm,
                linear=self.linear, ramp=(ramp or not warm) and solves == 0,
                on_step=None if self.contact is None else lambda _, x: self.contact.pair(x))
            solves += 1
            if not self.result.converged:
                raise NewtonFailure(self.result)
            return self.result.iterations

        if self.contact is None:
            solve()
        else:
            self.contact.pair(self.state.vec)
            try:
                settle(solve, self._mismatch, self.settings.for_route(True).rtol, close=0.0)
            except PairsUnsettled as err:
                raise NewtonFailure(dataclasses.replace(
                    self.result, converged=False, reason=str(err))) from None
        self.load.Set(self.pressure)

    def _mismatch(self) -> float:
        """Pair anew at the equilibrium found; the residual there with the new pairs,
        relative to the load."""
        self.contact.pair(self.state.vec)
        r = self.state.vec.CreateVector()
        self.residual(self.state.vec, r, self.pressure)
        return free_norm(r, self.free) / self.load_norm(self.pressure)

    def start_from(self, field) -> None:
        """The next solve starts at the full load from ``field`` (a displacement, e.g. that of
        the same part on another mesh; in the mixed formulation the dilatation its ``J - 1``,
        the pressure zero), and ramps from zero only if that fails."""
        self.u.Set(field)
        if self.mixed is not None:
            self.parts[1].Set(Det(Id(self.mesh.dim) + Grad(self.u)) - 1.0)
            self.parts[2].vec[:] = 0.0
        self._started = True

    def strain_energy_of_state(self) -> float:
        """``SE`` at the current state."""
        return float(self._se.Energy(self.state.vec))

    def strain_energy_gradient(self, out) -> None:
        """``out = ∂SE/∂x`` at the current state."""
        self._se.Apply(self.state.vec, out)

    def residual_density(self):
        """``t Dψ(x)[λ]`` at the current state and adjoint (a CF: the volume part of
        ``R(x; λ)``)."""
        psi = self.density(self.parts)
        terms = [psi.Diff(x, lam) for x, lam in zip(self.parts, self.adjoint_parts)]
        return self.thickness * sum(terms[1:], terms[0])

    def spring_terms(self):
        """The explicit shape terms of the boundary springs in ``-R(x; λ)``: with
        ``I = ∫_Γ (d̂·u)(d̂·λ) ds`` and ``w = 1/|Γ|`` frozen, ``-k w ∫_Γ (d̂·u)(d̂·λ) ds +
        k w² I ∫_Γ 1 ds`` (the quotient rule ``d(I/C) = dI/C - I dC/C²``), or None."""
        u, lam, total = self.u, self.lam, None
        for d, w, spring in self.boundary_springs:
            product = InnerProduct(d, u) * InnerProduct(d, lam)
            integral = float(Integrate(product * shape_ds(spring.region), self.mesh))
            k, wv = spring.stiffness, w.Get()
            term = (-k * wv * product + k * wv * wv * integral) * shape_ds(spring.region)
            total = term if total is None else total + term
        return total

