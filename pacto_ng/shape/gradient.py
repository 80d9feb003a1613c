"""A part's output displacement on its current shape, and its shape gradient by the adjoint.

State.  On the current shape Ω of the part (:class:`~pacto_ng.shape.deformation.ShapeSpace`
moves the mesh) the displacement ``u ∈ U`` (VectorH1 of order ``p``, zero where ``supports``
fix it) solves, for every test function ``v``,

    R(u; v) = t ∫_Ω ∂φ/∂G(∇u) : ∇v dx + t ∫_Γp P a(u) · v ds = 0,

with the run's strain-energy density ``φ`` (:func:`~pacto_ng.physics.energy.make_energy` of
the run's :class:`~pacto_ng.params.Parameters` on solid material everywhere,
:func:`~pacto_ng.post.part_analysis.solid_fields`, as
:class:`~pacto_ng.post.part_analysis.PartAnalysis` builds it), the thickness ``t`` of a 2D
part (1 in 3D), the wall pressure ``P`` on ``Γp`` with ``N`` the solid's outward normal
(:func:`~pacto_ng.physics.walls.outward_normal`) and

* ``fixed``: ``a(u) = N`` (the potential ``t ∫ P N · u ds``: a symmetric tangent);
* ``follower``: ``a(u) = cof(F̃) N``, ``F̃ = I + ∇_Γ u`` (``Grad(u).Trace()``; Nanson's
  formula ``n da = cof(F) N dA``, exact with the surface gradient: Bonet and Wood 2008,
  *Nonlinear continuum mechanics for finite element analysis*, 2nd ed., §4.2.5; the terms of
  :func:`~pacto_ng.physics.walls.follower_terms`): an unsymmetric tangent.

Newton's method with load continuation and the ``det F`` guard
(:func:`~pacto_ng.physics.newton.solve_with_continuation`) solves it, warm-started from the
last shape's state; the tangent ``K = ∂R/∂u`` comes from ``AssembleLinearization`` and is
factorised once and refactorised numerically (``Update``) with the same ordering afterwards.

Output.  ``Δ = Σ_k w_k d_k · ū_k`` over the ports (:class:`~pacto_ng.physics.loads.Port`:
region, direction ``d_k``, weight ``w_k``), ``ū_k`` the mean of ``u`` over a named boundary
``Γ_k`` (``∫_Γk u ds / |Γ_k|``) or its value at a named point.

Shape gradient (Céa's Lagrangian method; Allaire, Dapogny and Jouve 2021, *Handbook of
Numerical Analysis* 22, §3.3; the discrete version: the state and adjoint are finite element
functions that move with the mesh).  With the adjoint ``λ ∈ U`` solving the transposed
tangent system ``Kᵀ λ = ∂Δ/∂u`` (one solve with the state's factorisation), the Lagrangian

    L(Ω) = Σ_k w_k ∫_Γk (d_k · u - I_k/|Γ_k|) ds / |Γ_k| - R(u; λ),   I_k = ∫_Γk d_k · u ds,

(boundary ports only: a named point is a mesh vertex that moves with ``u``, whose value there
has no explicit shape dependence; nor has the term ``k (d̂ · u)(d̂ · λ)`` of an output spring
``k/2 (d̂ · u)²`` at a named point, which is in ``R`` and ``K`` but not written in ``L``) is
stationary in ``u`` and ``λ``, and its explicit shape
derivative (coefficients ``I_k``, ``|Γ_k|`` frozen) is the total one:
``dΔ[V] = ∂L/∂Ω[V]``, from
:meth:`~pacto_ng.shape.deformation.ShapeSpace.derivative` (``DiffShape``).  The first term
differentiates the mean: ``d(I/A) = dI/A - I dA/A²``.

The mechanism ratio.  The runs minimise ``-s Δ/SE``
(:class:`~pacto_ng.responses.MechanismRatio`), ``SE`` the stored strain energy of the state

    SE = t ∫_Ω φ(∇u) dx,      ∂SE/∂u [v] = t ∫_Ω ∂φ/∂G(∇u) : ∇v dx

(the potential of the residual's first term, ``½ u · K u`` for the linear model; an output
spring's energy is not part of it, as in :class:`~pacto_ng.responses.StrainEnergy`), summed
by the quadrature of the assembled forms, which ``DiffShape`` uses too (``Integrate`` takes
another: 1e-6 apart on a curved 2D mesh, and central differences 1e-5 to 2.5e-5 off).
For ``J = Δ/SE`` the adjoint solves

    Kᵀ λ = ∂J/∂u = (∂Δ/∂u - J ∂SE/∂u) / SE

(the same factorisation), and the Lagrangian, ``J`` and ``SE`` frozen as coefficients as
``I_k`` and ``|Γ_k|`` are,

    L(Ω) = (L_Δ(Ω) - J t ∫_Ω φ(∇u) dx) / SE - R(u; λ),

``L_Δ`` the port terms of ``L`` above, is stationary in ``u`` and ``λ``; its explicit shape
derivative is ``dJ[V]`` (the quotient rule ``d(Δ/SE) = (dΔ - J dSE)/SE`` on the explicit
parts).  Both objectives share the code: ``∂J = α ∂Δ - β ∂SE`` with ``(α, β) = (1, 0)`` for
``Δ`` and ``(1/SE, Δ/SE²)`` for ``Δ/SE``.

Output springs.  One at a named point adds its energy ``k/2 (d̂ · u)²`` to ``R`` (no
explicit shape term, above).  One on a boundary port is the runs' distributed spring of the
same total stiffness, ``k/2 (1/|Γ|) ∫_Γ (d̂ · u)² ds`` (:class:`~pacto_ng.physics.loads.
Spring`), with ``1/|Γ|`` of the current shape; its term ``k/|Γ| ∫_Γ (d̂·u)(d̂·λ) ds`` in
``R(u; λ)`` depends on the shape through the integral and through ``|Γ|``, and ``L`` carries
it as ``-k w ∫_Γ (d̂·u)(d̂·λ) ds + k w² J ∫_Γ ds`` with ``w = 1/|Γ|`` and
``J = ∫_Γ (d̂·u)(d̂·λ) ds`` frozen (the quotient rule, as for a port's mean).

The displacement formulation throughout (the mixed one of
:func:`~pacto_ng.physics.mixed.formulation_for` is not shape-differentiated here).
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np
from ngsolve import (L2, VOL, BilinearForm, CF, Cof, Grad, GridFunction, Id, InnerProduct,
                     Integrate, LinearForm, Parameter, Variation, VectorH1, dx)

from ..errors import InputError
from ..parallel import free_norm
from ..physics.energy import make_energy
from ..physics.equilibrium import NewtonFailure
from ..physics.loads import Port
from ..physics.mechanics import Supports
from ..physics.newton import solve_with_continuation
from ..physics.quadrature import integration_rules
from ..physics.spaces import dirichlet_options
from ..physics.walls import outward_normal
from ..post.part_analysis import CONTACT_CYCLES, solid_fields
from .contact_term import ShapeContact
from .deformation import ShapeSpace, shape_ds, shape_dx

KINDS = ("fixed", "follower")
#: the objectives whose shape gradient :meth:`PartResponse.gradient` gives: ``Δ`` and ``Δ/SE``
OBJECTIVES = ("delta", "ratio")


def _ports(mesh, ports) -> tuple[Port, ...]:
    """``ports`` as a tuple of Ports on named boundaries or points of ``mesh`` (ValueError
    otherwise)."""
    ports = (ports,) if isinstance(ports, Port) else tuple(ports)
    if not ports or not all(isinstance(p, Port) for p in ports):
        raise ValueError("ports: give a Port or a non-empty tuple of Ports")
    points = mesh.GetBBBoundaries() if mesh.dim == 3 else mesh.GetBBoundaries()
    for p in ports:
        if p.region not in mesh.GetBoundaries() and p.region not in points:
            raise ValueError(f"port '{p.region}' is neither a boundary nor a named point of the "
                             f"{mesh.dim}D mesh")
        if len(p.direction) != mesh.dim:
            raise ValueError(f"port '{p.region}': {len(p.direction)} direction components on "
                             f"a {mesh.dim}D mesh")
    return ports


def checked_objective(objective: str) -> str:
    """``objective`` if it is one of :data:`OBJECTIVES` (ValueError otherwise)."""
    if objective not in OBJECTIVES:
        raise ValueError(f"objective must be one of {', '.join(OBJECTIVES)}, not {objective!r}")
    return objective


class PartResponse:
    """The state, the output ``Δ``, the strain energy ``SE`` and the shape gradients of ``Δ``
    and ``Δ/SE`` of a part (see the module).

    Parameters
    ----------
    mesh : ngsolve.Mesh
        The part (2D: plane strain or stress and thickness from ``params``; 3D).  Its current
        deformation (``SetDeformation``) is the shape every :meth:`solve` sees.
    params : pacto_ng.params.Parameters
        The run's parameters: model (not ``auto``), E1, ν, plane, thickness, material, Newton's
        settings, order.
    supports : Supports
        Dirichlet conditions of the displacement by region name.
    ports : Port or tuple of Port
        The output (boundaries or named points, with their output springs).
    pressure : float
        The wall pressure ``P`` (negative: suction).
    kind : {"fixed", "follower"}
        The pressure's load.
    boundary : str
        The wetted wall ``Γp``.
    order : int, optional
        Displacement order (default ``params.order``, else 1).

    Attributes: ``u``, ``lam`` (GridFunctions of the state and the adjoint), ``delta`` and
    ``strain_energy`` (the last solve's ``Δ`` and ``SE``), ``result`` (its
    :class:`~pacto_ng.physics.newton.NewtonResult`), ``free`` (numpy mask of the free
    displacement dofs), ``thickness``, ``kind``.
    """

    def __init__(self, mesh, *, params, supports: Supports, ports, pressure: float,
                 kind: str = "fixed", boundary: str = "pressure", order: int | None = None):
        if kind not in KINDS:
            raise ValueError(f"kind must be one of {', '.join(KINDS)}, not {kind!r}")
        if boundary not in mesh.GetBoundaries():
            raise ValueError(f"the part has no '{boundary}' boundary to apply the pressure on")
        if not math.isfinite(pressure):
            raise ValueError(f"pressure must be finite (got {pressure!r})")
        if params.model == "auto":
            raise InputError("model: auto is chosen by a run; give the model the run used")
        if params.formulation == "mixed":
            raise InputError("formulation: the shape gradient is of the displacement "
                             "formulation; set formulation=displacement")
        self.mesh, self.kind, self.boundary = mesh, kind, boundary
        self.ports = _ports(mesh, ports)
        self.thickness = float(params.thickness) if mesh.dim == 2 else 1.0
        self.fes = VectorH1(mesh, order=int(order or params.order or 1),
                            **dirichlet_options(mesh, supports))
        self.free = np.array(list(self.fes.FreeDofs()), dtype=bool)
        if self.free.all():
            raise ValueError("the part has no supports: add a clamp or fixed boundary")
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
        self.u, self.lam = GridFunction(self.fes), GridFunction(self.fes)
        self.a, self._se = self._tangent_form(kind == "fixed"), self._energy_form()
        self.contact: ShapeContact | None = None
        self._E1 = float(params.E1)
        self._inverse = None
        self._tangent_current = False
        self._trial = GridFunction(self.fes)
        self._guard = None if guard is None else guard(Grad(self._trial), self.coeffs)
        self._points = mesh.MapToAllElements(integration_rules(2 * self.fes.globalorder), VOL)
        self.delta, self.strain_energy, self.result = math.nan, math.nan, None
        self._started = False
        self._output, self._sizes = None, ()

    # -- the forms -----------------------------------------------------------------------------
    def _traction(self, u):
        """``a(u)``: ``N`` (fixed) or ``cof(I + ∇_Γ u) N`` (follower)."""
        if self.kind == "fixed":
            return self.normal
        return Cof(Id(self.mesh.dim) + Grad(u).Trace()) * self.normal

    def _tangent_form(self, symmetric: bool):
        """The residual ``R(u; v)`` as a BilinearForm (Variation of the potential, and the
        follower term as a residual term); ``symmetric``: its matrix in symmetric storage."""
        u, v = self.fes.TnT()
        t, P = self.thickness, self.sign * self.load
        a = BilinearForm(self.fes, symmetric=symmetric)
        a += Variation(t * self.energy(Grad(u), self.coeffs) * shape_dx())
        if self.kind == "fixed":
            a += Variation(t * P * InnerProduct(self.normal, u) * shape_ds(self.boundary))
        else:
            a += t * P * InnerProduct(self._traction(u), v) * shape_ds(self.boundary)
        self._boundary_springs = []
        for p in self.ports:  # output springs
            for spring in p.springs():
                if p.region not in self.mesh.GetBoundaries():
                    a += Variation(spring.energy(self.mesh, u))  # at a named point
                    continue
                # on a boundary: k/2 (1/|Γ|) ∫_Γ (d̂·u)² ds, 1/|Γ| of the current shape
                d = np.asarray(spring.direction, dtype=float)
                term = (CF(tuple(d / np.linalg.norm(d))), Parameter(1.0), spring)
                self._boundary_springs.append(term)
                a += Variation(0.5 * spring.stiffness * term[1] * InnerProduct(term[0], u) ** 2
                               * shape_ds(spring.region))
        return a

    def _spring_terms(self):
        """The explicit shape terms of the boundary springs in ``-R(u; λ)``: with
        ``I = ∫_Γ (d̂·u)(d̂·λ) ds`` and ``w = 1/|Γ|`` frozen, ``-k w ∫_Γ (d̂·u)(d̂·λ) ds +
        k w² I ∫_Γ 1 ds`` (the quotient rule ``d(I/C) = dI/C - I dC/C²``, as for a port's
        mean)."""
        u, lam, total = self.u, self.lam, None
        for d, w, spring in self._boundary_springs:
            product = InnerProduct(d, u) * InnerProduct(d, lam)
            integral = float(Integrate(product * shape_ds(spring.region), self.mesh))
            k, wv = spring.stiffness, w.Get()
            term = (-k * wv * product + k * wv * wv * integral) * shape_ds(spring.region)
            total = term if total is None else total + term
        return total

    def _measure_springs(self) -> None:
        """``w = 1/|Γ|`` of every boundary spring on the current shape."""
        for _, w, spring in self._boundary_springs:
            w.Set(1.0 / float(Integrate(CF(1.0) * shape_ds(spring.region), self.mesh)))

    def _outputs(self):
        """``(f, [(port, |Γ_k| or None)])``: the vector with ``Δ = f · u`` (and ``∂Δ/∂u``) on
        the current shape, and each port's boundary measure (None for a named point)."""
        mesh, v = self.mesh, self.fes.TestFunction()
        lf, sizes = LinearForm(self.fes), []
        for p in self.ports:
            d = CF(tuple(float(c) for c in p.direction))
            if p.region in mesh.GetBoundaries():
                size = float(Integrate(CF(1.0) * shape_ds(p.region), mesh))
                lf += (p.weight / size) * InnerProduct(d, v) * shape_ds(p.region)
            else:
                size = None
                points = mesh.BBBoundaries if mesh.dim == 3 else mesh.BBoundaries
                lf += p.weight * InnerProduct(d, v) * dx(definedon=points(p.region))
            sizes.append((p, size))
        lf.Assemble()
        return lf.vec, sizes

    def _energy_form(self):
        """``SE(u) = t ∫_Ω φ(∇u) dx`` as a BilinearForm (the Variation of the residual's own):
        ``Energy`` gives ``SE``, ``Apply`` ``∂SE/∂u``, by the quadrature of the assembly (that
        of ``DiffShape``; ``Integrate`` takes another, and differs by ~1e-6 on a curved mesh)."""
        u = self.fes.TrialFunction()
        form = BilinearForm(self.fes, symmetric=True)
        form += Variation(self.thickness * self.energy(Grad(u), self.coeffs) * shape_dx())
        return form

    def _scales(self, objective) -> tuple[float, float]:
        """``(α, β)`` with ``J``'s partial derivatives ``α ∂Δ - β ∂SE`` (in ``u`` and in the
        shape): ``(1, 0)`` for ``Δ``, ``(1/SE, Δ/SE²)`` for ``Δ/SE``; for a combination
        ``{name: weight}`` the weighted sums (one adjoint and one shape derivative for all)."""
        if isinstance(objective, dict):
            pairs = [(w, self._scales(name)) for name, w in objective.items()]
            return (sum(w * a for w, (a, _) in pairs), sum(w * b for w, (_, b) in pairs))
        if checked_objective(objective) == "delta":
            return 1.0, 0.0
        if not self.strain_energy > 0.0:
            raise ValueError(f"the ratio Δ/SE needs a strained state (SE = "
                             f"{self.strain_energy!r})")
        return 1.0 / self.strain_energy, self.delta / self.strain_energy ** 2

    def use_contact(self, space: ShapeSpace, names) -> None:
        """The walls ``names`` in frictionless self-contact from now on, the shape's
        deformation that of ``space`` (:mod:`pacto_ng.shape.contact_term`): in the state, its
        tangent and adjoint, and the shape gradient."""
        self.contact = ShapeContact(self.fes, space, names, E1=self._E1,
                                    thickness=self.thickness)
        self.a = self._tangent_form(False)  # full storage: the contact's tangent is added
        self.linear, self._inverse = False, None

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
                self._inverse = tangent.Inverse(self.fes.FreeDofs(), inverse="umfpack")
            else:
                self._inverse.Update()
        elif self._inverse is None:
            inverse = "sparsecholesky" if self.kind == "fixed" else "umfpack"
            self._inverse = self.a.mat.Inverse(self.fes.FreeDofs(), inverse=inverse)
        else:
            self._inverse.Update()  # the same sparsity: numeric refactorisation only

    def solve_tangent(self, rhs, out):
        out.data = self._inverse * rhs

    def admissible(self, vec) -> bool:
        if self._guard is None:
            return bool(np.all(np.isfinite(vec.FV().NumPy())))
        self._trial.vec.data = vec
        vals = np.asarray(self._guard(self._points))
        return bool(np.all(np.isfinite(vals)) and np.all(vals > 0.0))

    def load_norm(self, load):
        """``|R(0)|`` on the free dofs at load factor ``load``: the external load."""
        zero, out = self.u.vec.CreateVector(), self.u.vec.CreateVector()
        zero[:] = 0.0
        self.residual(zero, out, load)
        return free_norm(out, self.free)

    # -- the response --------------------------------------------------------------------------
    def solve(self, ramp: bool = True) -> float:
        """Equilibrium on the current shape (warm-started from the last one's) and ``Δ``;
        NewtonFailure if Newton does not reach the pressure (with ``ramp`` False, if the warm
        start fails: no ramp from zero)."""
        self._measure_springs()
        # with contact: Newton with the pairs fixed, then paired anew, until they hold (from
        # the last pairing's equilibrium: no ramp from zero)
        for cycle in range(CONTACT_CYCLES if self.contact is not None else 1):
            if self.contact is not None and cycle == 0:  # later: paired by _pairs_hold
                self.contact.pair(self.u.vec)
            warm = self.result is not None or self._started
            self.result = solve_with_continuation(
                self, self.u.vec, self.pressure, self.settings, warm=warm, linear=self.linear,
                ramp=(ramp or not warm) and cycle == 0,
                on_step=None if self.contact is None else lambda _, x: self.contact.pair(x))
            if not self.result.converged:
                raise NewtonFailure(self.result)
            if self.contact is None or self._pairs_hold():
                break
        else:
            raise NewtonFailure(dataclasses.replace(
                self.result, converged=False,
                reason=f"the contact's pairs did not settle in {CONTACT_CYCLES} pairings"))
        self.load.Set(self.pressure)
        # the factorised tangent is the equilibrium's own if the problem is linear and Newton
        # assembled it on this shape
        self._tangent_current = self.linear and self.result.iterations > 0
        self._output, self._sizes = self._outputs()
        self.delta = float(InnerProduct(self._output, self.u.vec))
        self.strain_energy = float(self._se.Energy(self.u.vec))
        return self.delta

    def _pairs_hold(self) -> bool:
        """Pair anew at the equilibrium found; whether it holds with the new pairs (Newton's
        tolerance).  A load ramp pairs anew at each of its steps (``on_step``)."""
        self.contact.pair(self.u.vec)
        r = self.u.vec.CreateVector()
        self.residual(self.u.vec, r, self.pressure)
        tol = self.settings.for_route(True).rtol * self.load_norm(self.pressure)
        return free_norm(r, self.free) <= tol

    def start_from(self, field) -> None:
        """The next solve starts at the full load from ``field`` (a displacement, e.g. that of
        the same part on another mesh), and ramps from zero only if that fails."""
        self.u.Set(field)
        self._started = True

    def value(self, objective: str = "delta") -> float:
        """The last solve's objective: ``Δ`` (``"delta"``) or ``Δ/SE`` (``"ratio"``)."""
        alpha, _ = self._scales(objective)
        return alpha * self.delta

    def adjoint(self, objective: str = "delta") -> None:
        """``λ`` with ``Kᵀ λ = ∂J/∂u = α ∂Δ/∂u - β ∂SE/∂u`` (:meth:`_scales`) at the last
        equilibrium (the tangent refactorised at the converged state unless it is that
        already)."""
        if self.result is None:
            raise RuntimeError("solve the state before its adjoint")
        alpha, beta = self._scales(objective)
        rhs = self._output.CreateVector()
        rhs.data = alpha * self._output
        if beta:
            d_se = rhs.CreateVector()
            self._se.Apply(self.u.vec, d_se)  # ∂SE/∂u
            rhs.data -= beta * d_se
        if not self._tangent_current:
            self.assemble_tangent(self.u.vec, self.pressure)
            self._tangent_current = True
        inverse = self._inverse if self.kind == "fixed" else self._inverse.T
        self.lam.vec.data = inverse * rhs

    def lagrangian(self, objective: str = "delta"):
        """``L`` of the module at the last state and adjoint, as integrals over the current
        shape (their ``DiffShape`` is the shape gradient of ``objective``)."""
        u, lam, t = self.u, self.lam, self.thickness
        P = self.sign * self.pressure
        alpha, beta = self._scales(objective)
        L = (-t * self.energy(Grad(u), self.coeffs).Diff(u, lam)) * shape_dx()
        L += (-t * P * InnerProduct(self._traction(u), lam)) * shape_ds(self.boundary)
        for p, size in self._sizes:
            if size is None:
                continue  # a named point: no explicit shape dependence
            d = CF(tuple(float(c) for c in p.direction))
            mean = float(Integrate(InnerProduct(d, u) * shape_ds(p.region), self.mesh)) / size
            L += (alpha * p.weight / size) * (InnerProduct(d, u) - mean) * shape_ds(p.region)
        if beta:
            L += (-beta * t * self.energy(Grad(u), self.coeffs)) * shape_dx()
        springs = self._spring_terms()
        return L if springs is None else L + springs

    def gradient(self, space: ShapeSpace, objective="delta") -> np.ndarray:
        """``dJ/dV`` of ``J = Δ`` (``"delta"``), ``Δ/SE`` (``"ratio"``) or a weighted sum
        (``{"delta": a, "ratio": b}``) on ``space`` (its held dofs zeroed) at the last
        equilibrium: the adjoint solve and the shape derivative of :meth:`lagrangian`."""
        self.adjoint(objective)
        gradient = space.derivative(self.lagrangian(objective))
        if self.contact is not None:  # -∂/∂d R_c(u; d)[λ] (contact_term)
            gradient -= self.contact.shape_term(self.lam.vec)
        return gradient
