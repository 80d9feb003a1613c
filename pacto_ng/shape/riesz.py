"""The descent field of a shape derivative, the mesh quality of a deformation, and the step
control that keeps it.

Riesz map.  A shape derivative ``g`` (:meth:`~pacto_ng.shape.deformation.ShapeSpace.derivative`,
:meth:`~pacto_ng.shape.gradient.PartResponse.gradient`) is a dual vector: ``g(V) = g · V``.
Its Riesz representative ``θ ∈ X`` (zero on the held dofs) in the inner product

    b(θ, ψ) = ∫_Ω (ε(θ) : ε(ψ) + α θ · ψ) dx      (``elasticity``)
    b(θ, ψ) = ∫_Ω (∇θ : ∇ψ + α θ · ψ) dx          (``laplace``),

on the current shape Ω (the mesh moved by the space's deformation), solves
``b(θ, ψ) = g(ψ)`` for every ``ψ``: the "H¹ gradient" or extension-regularisation of the
shape gradient (Burger 2003, *Interfaces Free Bound.* 5, "A framework for the construction of
level set methods for shape optimization and reconstruction"; Allaire, Dapogny and Jouve
2021, *Handbook of Numerical Analysis* 22, "Shape and topology optimization").  ``b`` is symmetric positive definite on the
free dofs (``α > 0``), so ``g(θ) = b(θ, θ) > 0``: ``θ`` increases the functional of ``g``
and ``-θ`` decreases it, and ``θ`` is as smooth as the mesh's H¹ space allows (a raw
``g`` is concentrated at boundary nodes and would fold the mesh).

Quality.  The deformation ``d`` maps the reference mesh Ω0 onto Ω; its Jacobian
``det(I + ∇₀d)`` (``∇₀`` on Ω0) is the ratio of the moved to the reference element measure at
each point, and a non-positive value is a folded element.  It is evaluated at the integration
points of Ω0 **with the deformation unset** (the NGSolve notes: with it set, ``Grad`` is taken
on the moved mesh).  The step control takes the largest ``s = s_max / 2^k`` with
``min det(I + ∇₀(d + sθ)) ≥ q_min``.
"""
from __future__ import annotations

import numpy as np
from ngsolve import (VOL, BilinearForm, BitArray, Det, Grad, GridFunction, Id, InnerProduct,
                     Sym, dx)

from ..physics.quadrature import integration_rules
from .deformation import ShapeSpace

KINDS = ("elasticity", "laplace")


class RieszMap:
    """``g ↦ θ``, the Riesz representative of a shape derivative (see the module).

    Parameters
    ----------
    space : ShapeSpace
        The shape space: ``θ`` lives in ``space.space`` with its held dofs zero.
    alpha : float
        The weight ``α > 0`` of the ``L²`` term (units of 1/length²: ``1/L²`` for a part of
        size ``L`` balances the two terms).
    kind : {"elasticity", "laplace"}
        ``ε(θ):ε(ψ)`` or ``∇θ:∇ψ``.

    The form is assembled and refactorised (same ordering) on the current shape at every call:
    the mesh moves between calls.
    """

    def __init__(self, space: ShapeSpace, *, alpha: float = 1.0, kind: str = "elasticity"):
        if kind not in KINDS:
            raise ValueError(f"kind must be one of {', '.join(KINDS)}, not {kind!r}")
        if not alpha > 0:
            raise ValueError(f"alpha must be positive (got {alpha!r})")
        self.space, self.alpha, self.kind = space, float(alpha), kind
        theta, psi = space.space.TnT()
        if kind == "elasticity":
            grad = InnerProduct(Sym(Grad(theta)), Sym(Grad(psi)))
        else:
            grad = InnerProduct(Grad(theta), Grad(psi))
        self.form = BilinearForm(space.space, symmetric=True)
        self.form += (grad + self.alpha * InnerProduct(theta, psi)) * dx
        self.field = GridFunction(space.space)
        self.inverse = None

    def __call__(self, g, hold=None) -> np.ndarray:
        """The coefficients of ``θ`` with ``b(θ, ψ) = g · ψ`` on the current shape (held dofs
        of ``θ`` zero; the entries of ``g`` on held dofs are ignored).  ``hold``, a boolean
        mask of dofs, holds these too for this call only (``θ`` solves the same problem on
        the smaller space: the active set of a box bound, :func:`~.refine.refine`)."""
        g = np.asarray(g, dtype=float)
        if g.shape != (self.space.ndof,):
            raise ValueError(f"riesz: {g.shape} entries for a space of {self.space.ndof}")
        held = self.space.held if hold is None else self.space.held | np.asarray(hold, bool)
        self.form.Assemble()
        if hold is not None and np.any(held & ~self.space.held):
            free = BitArray(self.space.ndof)
            free.Clear()
            for dof in np.flatnonzero(~held):
                free.Set(int(dof))
            inverse = self.form.mat.Inverse(free, inverse="sparsecholesky")
        else:
            if self.inverse is None:
                self.inverse = self.form.mat.Inverse(self.space.space.FreeDofs(),
                                                     inverse="sparsecholesky")
            else:
                self.inverse.Update()  # the same sparsity: numeric refactorisation only
            inverse = self.inverse
        rhs = self.field.vec.CreateVector()
        rhs.FV().NumPy()[:] = g
        self.field.vec.data = inverse * rhs
        out = self.field.vec.FV().NumPy().copy()
        out[held] = 0.0
        return out


class Quality:
    """``min det(I + ∇₀d)`` over the integration points of the reference mesh (see the
    module) for deformations ``d`` of ``space``; the space's own deformation is left set."""

    def __init__(self, space: ShapeSpace):
        self.space = space
        self.trial = GridFunction(space.space)
        self.jacobian = Det(Id(space.mesh.dim) + Grad(self.trial))
        rules = integration_rules(2 * space.space.globalorder)
        self.space.mesh.UnsetDeformation()
        self.points = space.mesh.MapToAllElements(rules, VOL)
        self.space.mesh.SetDeformation(space.deformation)

    def __call__(self, values) -> float:
        """The lowest Jacobian of the deformation with coefficients ``values``."""
        self.trial.vec.FV().NumPy()[:] = np.asarray(values, dtype=float)
        mesh = self.space.mesh
        mesh.UnsetDeformation()
        try:
            return float(np.min(np.asarray(self.jacobian(self.points))))
        finally:
            mesh.SetDeformation(self.space.deformation)


def step_length(quality: Quality, shape, direction, s_max: float, *, q_min: float = 0.3,
                halvings: int = 30) -> tuple[float, float]:
    """``(s, q)``: the largest ``s = s_max / 2^k`` (``k ≤ halvings``) with
    ``q = quality(shape + s direction) ≥ q_min``; ``(0.0, quality(shape))`` if none is."""
    shape = np.asarray(shape, dtype=float)
    direction = np.asarray(direction, dtype=float)
    s = float(s_max)
    for _ in range(halvings + 1):
        q = quality(shape + s * direction)
        if q >= q_min:
            return s, q
        s *= 0.5
    return 0.0, quality(shape)
