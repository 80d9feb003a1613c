"""The backward pass of the mechanics block: the adjoint state and ``λᵀ ∂R/∂field``.

The discrete adjoint: with ``Kᵀ λ = ∂J/∂u`` (K the tangent at the converged state,
factorised once and reused for every response),

    dJ/dρ = ∂J/∂ρ - λᵀ ∂R/∂ρ,
    λᵀ ∂R/∂ρ = ∂/∂ρ [ t ∫ ∂φ/∂u[λ] - s b·λ + r(u, λ; fields, s) dΩ ],

the gradient of ``L(ρ) = ∫ density(u; ρ).Diff(u, λ) + t r(u, λ; ρ)`` with ``u`` and ``λ`` held
fixed: ``Apply`` of a ``Variation`` form of ``L`` on the field's own space (automatic
differentiation in ρ).  The residual density is built once with the
trial/test functions (residual, tangent) and once with ``(u, λ)`` as GridFunctions
(sensitivity), so its field dependence is differentiated by NGSolve too.  ``residual_terms``
must not depend on the fields (they are left out of ``∂R/∂ρ``).

The terms ``λᵀ ∂R/∂field`` are computed by
:class:`~pacto_ng.physics.sensitivities.FieldSensitivities`, each field by its route.
:class:`Adjoint` is a part of :class:`~pacto_ng.physics.mechanics.Mechanics`: it solves with the
tangent factorised by :class:`~pacto_ng.physics.equilibrium.Equilibrium` (at the converged state)
and, for the self-adjoint shortcut, uses its unit external load vector.
"""
from __future__ import annotations

import numpy as np

from ..parallel import total
from .sensitivities import FieldSensitivities


class Adjoint:
    """The backward pass of :class:`~pacto_ng.physics.mechanics.Mechanics` (see the module)."""

    def _start_adjoint(self):
        """The adjoint state and the sensitivity forms (built once, with the block)."""
        from ngsolve import GridFunction

        self._adjoint_ready = False  # the tangent at the current state is factorised
        self.lam = GridFunction(self.space)
        # λᵀ ∂R/∂field, each field by its route (sensitivities.py)
        self._sens = FieldSensitivities(self, self._coupling, self._lin)
        self.self_adjoint_shortcut = True  # compliance: λ = u / s without a solve
        self.adjoint_solves_skipped = 0  # adjoints that were the primal (compliance)
        self.adjoint_solves = 0  # adjoints solved with the factorised tangent

    def adjoint_lagrangian(self, coeffs):
        """``λᵀ R(u)`` per unit area with the fields ``coeffs`` (u, λ: the block's states)."""
        dens = self.volume_density(self.gfx, coeffs)
        # the directional derivative in every component of the state (a Diff in the compound
        # GridFunction itself would be zero)
        lag = sum(dens.Diff(x, lam) for x, lam in zip(self.components(self.gfx),
                                                     self.components(self.lam)))
        if self.has_residual_density:
            lag = lag + self.residual_density(self.gfu, self.displacement(self.lam),
                                              coeffs)  # linear in λ
        return lag

    def _ensure_tangent(self):
        """The tangent at the converged state, ready to solve with (once per forward pass):
        factorised, or preconditioned by the factorisation of Newton's last full step."""
        if self._adjoint_ready:
            return
        # a linear problem's tangent does not depend on u: the one Newton factorised is exact;
        # a nonlinear one's is near the one Newton factorised at this design (its last full
        # step's), whose factorisation then preconditions it
        if not (self.linear and self._tangent_at is not None):
            self.assemble_tangent(self.gfx.vec, self.target, near=self._tangent_at is not None)
        self._adjoint_ready = True

    def adjoint(self, dJdu):
        """Solve ``Kᵀ λ = dJ/du`` with the tangent at the solution; returns λ (a vector).

        Self-adjoint shortcut: for a linear problem with design-independent loads, when
        ``dJ/du = c f`` (compliance) the adjoint is ``λ = (c / s) u`` with no solve at all
        (``K u = s f``).  ``adjoint_solves_skipped`` counts the shortcuts, ``adjoint_solves``
        the solves.  On a distributed mesh the test is made on every rank's part (both vectors
        are assembled from the same element contributions, so ``dJ/du = c f`` holds part by part
        or not at all) with ``c`` from the sums over the ranks.
        """
        lam = self.gfx.vec.CreateVector()
        f = self._f_unit
        if (self.self_adjoint_shortcut and self.linear and self._fixed_loads and self.symmetric
                and f is not None and self.target != 0):
            g = dJdu.FV().NumPy()
            gf, ff = g[self.free], f[self.free]
            f2 = total(self.mesh, ff @ ff)
            c = total(self.mesh, gf @ ff) / f2 if f2 > 0 else 0.0
            resid = gf - c * ff
            if f2 > 0 and total(self.mesh, resid @ resid) <= 1e-24 * max(
                    total(self.mesh, gf @ gf), 1e-300):
                lam.data = (c / self.target) * self.gfx.vec
                self.adjoint_solves_skipped += 1
                return lam
        self._ensure_tangent()
        self._solver.solve(dJdu, lam, transpose=True)
        self.adjoint_solves += 1
        return lam

    def field_sensitivity(self, name) -> np.ndarray:
        """``λᵀ ∂R/∂field`` (numpy) for the current ``u`` (``gfu``), ``λ`` (``lam``) and design."""
        g = self._sens.minus(self.fields[self.inputs.index(name)])
        return -(g if isinstance(g, np.ndarray) else g.FV().NumPy())

    def backward(self, dJdu):
        lam = self.adjoint(dJdu)
        self.lam.vec.data = lam
        return tuple(self._sens.minus(f) for f in self.fields)
