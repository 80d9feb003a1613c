"""The backward pass's field terms ``λᵀ ∂R/∂field`` of a mechanics block, each by its route.

* general: :class:`FieldGradient`, automatic differentiation of ``L(field) = λᵀ R(u; field)``
  (``Mechanics.adjoint_lagrangian``) with ``u`` and ``λ`` held fixed;
* a field that enters only through a body load linear in it (the energy does not read it, no
  residual density): ``-s Bᵀλ`` of the :class:`~pacto_ng.physics.body_coupling.BodyCoupling`;
* an element-wise field of a quadratic energy (``Mechanics.linear_system``):
  ``∫ (∂C/∂ρ ∇u) : ∇λ - s t ∂(b·λ)/∂ρ``, from element matrices once they are built.
"""
from __future__ import annotations

from .body_coupling import BodyCoupling


class FieldGradient:
    """``∫ ∂L/∂field [q] dΩ`` for every test function ``q`` of a field's space, by automatic
    differentiation: ``L(coeffs)`` (a CF) with the field replaced by its trial function is the
    integrand of a ``Variation`` form, whose ``Apply`` at the field's values is the gradient.

    Symbolic ``.Diff(field)`` of an already differentiated density blows the CF up: measured,
    Wang, 2906 triangles, λᵀ∂R/∂ρ 4.8 s per assembly as a LinearForm of ``.Diff``, 0.07 s this
    way, equal to 6e-16.  Used like a LinearForm: ``Assemble()``, then ``vec``.
    """

    def __init__(self, field, make_integrand, coeffs, DX):
        from ngsolve import BilinearForm, Variation

        c = dict(coeffs)
        c[field.name] = field.space.TrialFunction()
        self.field = field
        self.form = BilinearForm(field.space)
        self.form += Variation(make_integrand(c).Compile() * DX)
        self.vec = field.gf.vec.CreateVector()

    def Assemble(self):
        self.form.Apply(self.field.gf.vec, self.vec)


class FieldSensitivities:
    """``-λᵀ ∂R/∂field`` for every field of ``mech`` at its current ``u`` (``gfu``), ``λ``
    (``lam``), load factor and design (forms built once)."""

    def __init__(self, mech, coupling: BodyCoupling | None, lin):
        self.mech, self.lin = mech, lin
        self._forms = {}
        for f in mech.fields:
            if coupling is not None and f is coupling.field and not mech.has_residual_density:
                # only the body load depends on this field: λᵀ∂R/∂p = -s Bᵀλ
                self._forms[f.name] = coupling
            elif lin is not None and f.name in lin.field_names:
                # λᵀ ∂R/∂ρ = ∫ (∂C/∂ρ ∇u) : ∇λ - s t ∂(b·λ)/∂ρ (quadratic energy, b·u linear)
                extra = None
                if mech.body is not None and coupling is None:
                    extra = (-mech.load * mech.thickness * mech.body(mech.lam, mech.coeffs)).Diff(
                        f.gf, mech.one)
                self._forms[f.name] = lin.field_form(f.name, mech.gfu, mech.lam, 1.0, extra)
            else:
                self._forms[f.name] = FieldGradient(f, mech.adjoint_lagrangian, mech.coeffs,
                                                    mech.DX)

    def minus(self, f):
        """``-λᵀ ∂R/∂field`` (the backward pass's term): a numpy array for an element-wise
        field, else a vector of the field's space."""
        if self.lin is not None:
            self.lin.prepare_fields()
        lf = self._forms[f.name]  # a LinearForm, a FieldGradient or a BodyCoupling
        if isinstance(lf, BodyCoupling):
            v = f.gf.vec.CreateVector()
            lf.adjoint_term(self.mech.lam.vec, self.mech.load.Get(), v)
            return v
        lf.Assemble()
        if f.space is self.mech.l2:
            return -lf.vec.FV().NumPy().copy()
        v = lf.vec.CreateVector()
        v.data = -1.0 * lf.vec
        return v
