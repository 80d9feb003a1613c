"""Responses (scalar blocks): compliance, output displacement, strain energy, the mechanism
ratio −sΔ/SE, and volume.

Each returns a float from ``forward`` and, from ``backward(g)``, ``g`` times its partial
derivatives: a vector on the displacement space for ``u`` and numpy arrays for element fields.
The displacement part is what the mechanics block's adjoint solve consumes.  Every response
holds on 2D and 3D meshes alike: the mechanics block's thickness ``t`` is 1 on a 3D mesh (its
integrals are over the volume), and ``Volume``'s element measures are areas in 2D and volumes
in 3D.
"""
from __future__ import annotations

import numpy as np

from .parallel import total
from .physics.sensitivities import FieldGradient


class LinearFunctional:
    """``J = ℓ(u)`` for a design-independent linear functional ℓ (assembled once).

    Compliance ``f·u`` (ℓ = the external load's work) and an output displacement ``d·u`` at a
    port (ℓ = the port functional) are both of this form.
    """

    def __init__(self, mech, terms, inputs=None, output="J"):
        from ngsolve import LinearForm

        # default input: the mechanics block's displacement
        self.inputs = tuple(inputs) if inputs is not None else (mech.output,)
        self.output = output
        v = mech.displacement(mech.space.TestFunction())
        lf = LinearForm(mech.space)
        lf += terms(v)
        lf.Assemble()
        self.vec = lf.vec

    def forward(self, u):
        return float(self.vec.InnerProduct(u))

    def backward(self, g):
        out = self.vec.CreateVector()
        out.data = float(g) * self.vec
        return (out,)


def compliance(mech, output="compliance"):
    """End compliance ``f·u`` of the design-independent point/edge loads at full load."""
    if not mech.loads:
        raise ValueError("compliance needs at least one point or edge load")

    def terms(v):
        tot = None
        for ld in mech.loads:
            w = ld.work(mech.mesh, v)
            tot = w if tot is None else tot + w
        return tot

    return LinearFunctional(mech, terms, output=output)


def output_displacement(mech, port, output="delta"):
    """``Δ = d·u`` at the port (a named point, or the mean over a named boundary)."""
    return LinearFunctional(mech, lambda v: port.functional(mech.mesh, v), output=output)


class StrainEnergy:
    """Stored strain energy ``SE = t ∫ φ(∇u; fields) dΩ`` (the springs are not part of it; in
    the mixed formulation ``φ`` of the modified gradient, of the whole state:
    :meth:`~pacto_ng.physics.mechanics.Mechanics.stored_density`)."""

    def __init__(self, mech, output="se"):
        from ngsolve import BilinearForm, GridFunction, Integrate, Variation

        self.mech = mech
        self.inputs = (mech.output,) + mech.inputs
        self.output = output
        self.gfu = GridFunction(mech.space)  # the state (the displacement, or u, ϑ, p̃)
        self._dens = mech.stored_density(self.gfu).Compile()
        # ∂SE/∂u as the residual of the energy alone, Apply of a Variation form: the same
        # integrand and quadrature as a LinearForm of dens.Diff(u, v) (equal to 1e-14), but
        # 2-5x faster to evaluate (measured: benchmarks/profile_nonlinear.py strain_energy_ab)
        self._energy_form = BilinearForm(mech.space, symmetric=True)
        self._energy_form += Variation(
            mech.stored_density(mech.space.TrialFunction()).Compile() * mech.DX)
        self._du_vec = self.gfu.vec.CreateVector()
        # a quadratic energy (linear mechanics): SE, ∂SE/∂u and ∂SE/∂ρ from the tangent's C;
        # otherwise ∂SE/∂field by automatic differentiation (FieldGradient)
        lin = mech.linear_system  # (its energy is quadratic)
        self._quad = lin
        self._dfield = {}
        reads = mech.energy_fields
        for f in mech.fields:
            if not reads[f.name]:
                self._dfield[f.name] = None  # the energy does not read it (the pressure)
            elif lin is not None and f.name in lin.field_names:
                self._dfield[f.name] = lin.field_form(f.name, self.gfu, self.gfu, 0.5)
            else:
                self._dfield[f.name] = FieldGradient(
                    f, lambda c: mech.stored_density(self.gfu, c), mech.coeffs, mech.DX)
        self._integrate = Integrate

    @property
    def uses_linear_system(self) -> bool:
        """Whether SE's derivatives come from the mechanics block's quadratic linear system
        (``C`` per element) instead of automatic differentiation."""
        return self._quad is not None

    def forward(self, u, *fields):
        # the field values are those the mechanics block was last run with (same chain)
        self.gfu.vec.data = u
        # the integral of the (non-negative) energy density, also for a quadratic energy: the
        # quadratic form ½ u·K_φ u sums the entries of K u, which cancel where the structure
        # moves rigidly, and carried a round-off of 4e-11 of SE (measured on a PneuNet design;
        # finite differences at h = 1e-4 turned it into errors of 1e-6 - 8e-6)
        return total(self.mech.mesh, self._integrate(self._dens * self.mech.DX, self.mech.mesh))

    def backward(self, g):
        if self._quad is not None:
            self._quad.energy_gradient(self.gfu.vec, self._du_vec)
            self._quad.prepare_fields()
        else:
            self._energy_form.Apply(self.gfu.vec, self._du_vec)
        du = self._du_vec.CreateVector()
        du.data = float(g) * self._du_vec
        out = [du]
        for f in self.mech.fields:
            lf = self._dfield[f.name]  # a LinearForm, a FieldGradient or None (no dependence)
            if lf is None:
                out.append(None)
                continue
            lf.Assemble()
            if f.space is self.mech.l2:
                out.append(float(g) * lf.vec.FV().NumPy().copy())
            else:
                v = lf.vec.CreateVector()
                v.data = float(g) * lf.vec
                out.append(v)
        return tuple(out)


class MechanismRatio:
    """``f0 = -s Δ / SE`` (thesis eq. 3.9); ``scale`` s > 0 is fixed by the driver at iteration 0."""

    def __init__(self, inputs=("delta", "se"), output="objective", scale=1.0):
        self.inputs, self.output, self.scale = tuple(inputs), output, float(scale)

    def forward(self, delta, se):
        self._d, self._se = float(delta), float(se)
        return -self.scale * self._d / self._se

    def backward(self, g):
        return (-g * self.scale / self._se, g * self.scale * self._d / self._se ** 2)


class Scale:
    """``J = s · a`` for a scalar ``a`` (e.g. a maximised displacement as ``-Δ``)."""

    def __init__(self, factor, inputs, output):
        self.factor, self.inputs, self.output = float(factor), tuple(inputs), output

    def forward(self, a):
        return self.factor * float(a)

    def backward(self, g):
        return (self.factor * g,)


class Volume:
    """Volume constraint ``Σ a_e ρ̄_e / (V* ) - 1`` over the design elements (``V* = f_v Σ a_e``)."""

    def __init__(self, field, volfrac, inputs=("rho_bar",), output="volume"):
        if not 0.0 < volfrac < 1.0:
            raise ValueError(f"volfrac must lie in (0, 1) (got {volfrac})")
        self.inputs, self.output = tuple(inputs), output
        self.mesh = field.mesh
        self.w = np.where(field.design, field.areas, 0.0)
        self.total = total(self.mesh, self.w.sum())
        self.volfrac = volfrac

    def fraction(self, rho):
        return total(self.mesh, self.w @ rho) / self.total

    def forward(self, rho):
        return self.fraction(rho) / self.volfrac - 1.0

    def backward(self, g):
        return (g * self.w / (self.total * self.volfrac),)
