"""A body load that is linear in one field and reads no other: the load vector as ``B p``.

``t ∫ b(v; fields) dΩ = B p`` with the design-independent mixed matrix ``B = t ∫ b(v; q) dΩ``
(trial ``q`` in the field's space, test ``v`` in the displacement space), assembled once.
Example: the Darcy load ``b = -∇p``.  Then the load vector of a design is one product ``B p``
(no LinearForm assembly), and, when nothing else depends on the field (the energy does not
read it, no residual density), the adjoint term ``λᵀ ∂R/∂p = -s Bᵀλ`` is one transposed product
(no ``Variation`` form's ``Apply``; measured, 120 x 80 Q1: 38 ms against 0.2 ms).

Which field a body is linear in is declared (the body's ``linear_in`` attribute, or
:class:`~pacto_ng.physics.mechanics.Mechanics`' default: the one non-element-wise field the
declared energy does not read).  :meth:`BodyCoupling.build` verifies it on two random states of
all fields (the body's LinearForm against ``B p`` to 1e-12) and raises
:class:`~pacto_ng.physics.traits.DeclarationError` when it is wrong (NGSolve assembles ``B`` of a
body that is not linear in ``q`` without complaint, so the check is what catches it).
"""
from __future__ import annotations

import numpy as np

from ..parallel import everywhere, largest
from .linear_system import fields_restored, random_fields
from .traits import DeclarationError


class BodyCoupling:
    """``B`` of a body load linear in ``field`` alone (see the module)."""

    def __init__(self, mat, field, vec):
        self.mat, self.field, self.vec = mat, field, vec

    @classmethod
    def build(cls, mech, field, body_form, tol=1e-12):
        """Assemble ``B`` and verify it against ``body_form`` (the body's LinearForm)."""
        from ngsolve import BilinearForm

        if field.space is mech.l2:
            raise DeclarationError(f"a body load cannot be coupled through the element-wise "
                                   f"field '{field.name}'")
        c = dict(mech.coeffs)
        c[field.name] = field.space.TrialFunction()
        B = BilinearForm(trialspace=field.space, testspace=mech.space)
        v = mech.displacement(mech.space.TestFunction())
        B += (mech.thickness * mech.body(v, c)).Compile() * mech.DX
        B.Assemble()
        rng = np.random.default_rng(97531)
        Bp = body_form.vec.CreateVector()
        with fields_restored(mech):
            for _ in range(2):
                random_fields(mech, rng)
                body_form.Assemble()
                Bp.data = B.mat * field.gf.vec
                ref, got = body_form.vec.FV().NumPy(), Bp.FV().NumPy()
                scale = largest(mech.mesh, np.abs(ref))
                if not (scale > 0 and everywhere(mech.mesh, np.all(np.isfinite(got)))
                        and largest(mech.mesh, np.abs(ref - got)) <= tol * scale):
                    raise DeclarationError(
                        f"the body load is taken as linear in the field '{field.name}' alone, "
                        f"but its load vector is not B {field.name} on random fields (it reads "
                        f"another field, or is not linear in '{field.name}'); give the body "
                        f"callable the attribute linear_in = None for the general route")
        return cls(B.mat, field, body_form.vec.CreateVector())

    def load(self):
        """``t ∫ b(v) dΩ`` for the field's current values: ``B p``."""
        self.vec.data = self.mat * self.field.gf.vec
        return self.vec

    def adjoint_term(self, lam, load, out):
        """``out = s Bᵀλ`` (= ``-λᵀ ∂R/∂p``, the backward pass's contribution)."""
        out.data = load * (self.mat.T * lam)
