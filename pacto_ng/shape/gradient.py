"""A part's output displacement on its current shape, and its shape gradient by the adjoint.

State.  :class:`~pacto_ng.shape.state.PartState`: the part's equilibrium ``R(x; y) = 0`` on the
current shape, ``x`` the displacement ``u`` or the mixed formulation's ``(u, ϑ, p̃)``, with
the stored energy density ``ψ`` and the tangent ``K = ∂R/∂x``.

Output.  ``Δ = Σ_k w_k d_k · ū_k`` over the ports (:class:`~pacto_ng.physics.loads.Port`:
region, direction ``d_k``, weight ``w_k``), ``ū_k`` the mean of ``u`` over a named boundary
``Γ_k`` (``∫_Γk u ds / |Γ_k|``) or its value at a named point.

Shape gradient (Céa's Lagrangian method; Allaire, Dapogny and Jouve 2021, *Handbook of
Numerical Analysis* 22, §3.3; the discrete version: the state and adjoint are finite element
functions that move with the mesh).  With the adjoint ``λ`` (a state: ``λ ∈ U``, or three fields) solving the
transposed tangent system ``Kᵀ λ = ∂Δ/∂x`` (one solve with the state's factorisation), the
Lagrangian

    L(Ω) = Σ_k w_k ∫_Γk (d_k · u - I_k/|Γ_k|) ds / |Γ_k| - R(x; λ),   I_k = ∫_Γk d_k · u ds,

(boundary ports only: a named point is a mesh vertex that moves with ``u``, whose value there
has no explicit shape dependence; nor has the term ``k (d̂ · u)(d̂ · λ)`` of an output spring
``k/2 (d̂ · u)²`` at a named point, which is in ``R`` and ``K`` but not written in ``L``) is
stationary in ``x`` and ``λ``, and its explicit shape
derivative (coefficients ``I_k``, ``|Γ_k|`` frozen) is the total one:
``dΔ[V] = ∂L/∂Ω[V]``, from
:meth:`~pacto_ng.shape.deformation.ShapeSpace.derivative` (``DiffShape``).  The first term
differentiates the mean: ``d(I/A) = dI/A - I dA/A²``.

The mechanism ratio.  The runs minimise ``-s Δ/SE``
(:class:`~pacto_ng.responses.MechanismRatio`), ``SE = t ∫_Ω ψ(x) dx`` the stored strain
energy of the state (:mod:`~pacto_ng.shape.state`; an output spring's energy is not part of
it, as in :class:`~pacto_ng.responses.StrainEnergy`).  For ``J = Δ/SE`` the adjoint solves

    Kᵀ λ = ∂J/∂x = (∂Δ/∂x - J ∂SE/∂x) / SE

(the same factorisation), and the Lagrangian, ``J`` and ``SE`` frozen as coefficients as
``I_k`` and ``|Γ_k|`` are,

    L(Ω) = (L_Δ(Ω) - J t ∫_Ω ψ(x) dx) / SE - R(x; λ),

``L_Δ`` the port terms of ``L`` above, is stationary in ``x`` and ``λ``; its explicit shape
derivative is ``dJ[V]`` (the quotient rule ``d(Δ/SE) = (dΔ - J dSE)/SE`` on the explicit
parts).  Both objectives share the code: ``∂J = α ∂Δ - β ∂SE`` with ``(α, β) = (1, 0)`` for
``Δ`` and ``(1/SE, Δ/SE²)`` for ``Δ/SE``.

Output springs.  One at a named point has no explicit shape term (above), nor has one spread
about it over a support the shape holds.  One on a boundary
port, ``k/2 (1/|Γ|) ∫_Γ (d̂ · u)² ds`` with ``1/|Γ|`` of the current shape, has the term
``k/|Γ| ∫_Γ (d̂·u)(d̂·λ) ds`` in ``R(x; λ)``, which depends on the shape through the integral
and through ``|Γ|``; ``L`` carries it as ``-k w ∫_Γ (d̂·u)(d̂·λ) ds + k w² J ∫_Γ ds`` with
``w = 1/|Γ|`` and ``J = ∫_Γ (d̂·u)(d̂·λ) ds`` frozen (the quotient rule, as for a port's
mean).
"""
from __future__ import annotations

import numpy as np
from ngsolve import CF, InnerProduct, Integrate, LinearForm, dx

from ..physics.loads import Port
from .deformation import ShapeSpace, shape_ds
from .state import PartState

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


class PartResponse(PartState):
    """The state, the output ``Δ``, the strain energy ``SE`` and the shape gradients of ``Δ``
    and ``Δ/SE`` of a part (see the module); the parameters are
    :class:`~pacto_ng.shape.state.PartState`'s, ``ports`` a Port or a tuple of Ports (the
    output: boundaries or named points, with their output springs).

    Attributes beside the state's: ``lam`` (the adjoint's displacement; ``adjoint_state``
    the whole), ``delta`` and ``strain_energy`` (the last solve's ``Δ`` and ``SE``).
    """

    def __init__(self, mesh, *, params, supports, ports, pressure: float,
                 kind: str = "fixed", boundary: str = "pressure", order: int | None = None):
        super().__init__(mesh, params=params, supports=supports, ports=_ports(mesh, ports),
                         pressure=pressure, kind=kind, boundary=boundary, order=order)
        self.delta, self.strain_energy = float("nan"), float("nan")
        self._tangent_current = False
        self._output, self._sizes = None, ()

    def _outputs(self):
        """``(f, [(port, |Γ_k| or None)])``: the vector with ``Δ = f · x`` (and ``∂Δ/∂x``) on
        the current shape, and each port's boundary measure (None for a named point)."""
        mesh, v = self.mesh, self.split(self.states.TestFunction())[0]
        lf, sizes = LinearForm(self.states), []
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

    def _scales(self, objective) -> tuple[float, float]:
        """``(α, β)`` with ``J``'s partial derivatives ``α ∂Δ - β ∂SE`` (in ``x`` and in the
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

    # -- the response --------------------------------------------------------------------------
    def solve(self, ramp: bool = True) -> float:
        """Equilibrium on the current shape (:meth:`~pacto_ng.shape.state.PartState.
        equilibrium`) and ``Δ``."""
        self.equilibrium(ramp)
        # the factorised tangent is the equilibrium's own if the problem is linear and Newton
        # assembled it on this shape
        self._tangent_current = self.linear and self.result.iterations > 0
        self._output, self._sizes = self._outputs()
        self.delta = float(InnerProduct(self._output, self.state.vec))
        self.strain_energy = self.strain_energy_of_state()
        return self.delta

    def value(self, objective: str = "delta") -> float:
        """The last solve's objective: ``Δ`` (``"delta"``) or ``Δ/SE`` (``"ratio"``)."""
        alpha, _ = self._scales(objective)
        return alpha * self.delta

    def adjoint(self, objective: str = "delta") -> None:
        """``λ`` with ``Kᵀ λ = ∂J/∂x = α ∂Δ/∂x - β ∂SE/∂x`` (:meth:`_scales`) at the last
        equilibrium (the tangent refactorised at the converged state unless it is that
        already)."""
        if self.result is None:
            raise RuntimeError("solve the state before its adjoint")
        alpha, beta = self._scales(objective)
        rhs = self._output.CreateVector()
        rhs.data = alpha * self._output
        if beta:
            d_se = rhs.CreateVector()
            self.strain_energy_gradient(d_se)
            rhs.data -= beta * d_se
        if not self._tangent_current:
            self.assemble_tangent(self.state.vec, self.pressure)
            self._tangent_current = True
        self.solve_transposed(rhs, self.adjoint_state.vec)

    def lagrangian(self, objective: str = "delta"):
        """``L`` of the module at the last state and adjoint, as integrals over the current
        shape (their ``DiffShape`` is the shape gradient of ``objective``)."""
        u, lam, t = self.u, self.lam, self.thickness
        P = self.sign * self.pressure
        alpha, beta = self._scales(objective)
        L = -self.residual_density() * self.dx
        L += (-t * P * InnerProduct(self.traction(u), lam)) * shape_ds(self.boundary)
        for p, size in self._sizes:
            if size is None:
                continue  # a named point: no explicit shape dependence
            d = CF(tuple(float(c) for c in p.direction))
            mean = float(Integrate(InnerProduct(d, u) * shape_ds(p.region), self.mesh)) / size
            L += (alpha * p.weight / size) * (InnerProduct(d, u) - mean) * shape_ds(p.region)
        if beta:
            L += (-beta * t * self.density(self.parts)) * self.dx
        springs = self.spring_terms()
        return L if springs is None else L + springs

    def gradient(self, space: ShapeSpace, objective="delta") -> np.ndarray:
        """``dJ/dV`` of ``J = Δ`` (``"delta"``), ``Δ/SE`` (``"ratio"``) or a weighted sum
        (``{"delta": a, "ratio": b}``) on ``space`` (its held dofs zeroed) at the last
        equilibrium: the adjoint solve and the shape derivative of :meth:`lagrangian`."""
        self.adjoint(objective)
        gradient = space.derivative(self.lagrangian(objective))
        if self.contact is not None:  # -∂/∂d R_c(x; d)[λ] (contact_term)
            gradient -= self.contact.shape_term(self.adjoint_state.vec)
        return gradient
