r"""The Darcy pressure's load on the mechanics block, and the compliance of that load.

The pressure ``p`` is the output of :class:`~pacto_ng.physics.darcy.DarcyPressure`; it enters
:class:`~pacto_ng.physics.mechanics.Mechanics` as a field on its own space
(:meth:`~pacto_ng.physics.darcy.DarcyPressure.field`) through one of two loads:

Both hold in 2D (``t`` the thickness) and 3D (``t = 1``, the integral over the volume).

* fixed load (thesis eq. 3.8): body force ``b = -∇p``, external work ``t ∫ -∇p·u dΩ``
  (``f = -H p``), deformation independent (docs/theory.md §4).  :func:`darcy_body` gives it to
  :class:`~pacto_ng.physics.mechanics.Mechanics`, whose load factor multiplies it; the pressure
  is linear in ``(P_in, p_out)``, so the load factor scales the pressure itself.
* follower load (docs/theory.md §4, beyond the thesis): the spatial body force ``-∇_x p``
  acting on the deformed body, pulled back to the reference configuration, ``-J F⁻ᵀ ∇_X p``
  per unit reference volume (:func:`darcy_follower`).  It has no potential: it is a residual
  term of :class:`~pacto_ng.physics.mechanics.Mechanics` with an unsymmetric tangent (the load
  stiffness) and enters the sensitivity through ``λᵀ ∂R/∂p``.

:class:`Compliance` is the end compliance of the deformation-independent load, and
:func:`for_case` builds a case's pressure block, its field and its load from
:class:`~pacto_ng.physics.darcy.DarcySettings`.
"""
from __future__ import annotations

import numpy as np

from ..parallel import total
from .darcy import DarcyPressure, DarcySettings


def darcy_body(p_name: str = "p"):
    r"""The ``body`` callable of :class:`~pacto_ng.physics.mechanics.Mechanics` for the Darcy load.

    Returns ``(u, coeffs) -> -∇p · u``: the body-force potential density of ``b = -∇p``
    (thesis eq. 3.8), deformation independent (docs/theory.md §4).  Mechanics multiplies it by the
    thickness and the load factor, so the external work is ``s t ∫ -∇p·u dΩ``.
    """
    def body(u, coeffs):
        from ngsolve import InnerProduct, grad

        if p_name not in coeffs:
            raise ValueError(f"p_name: '{p_name}' is not a field of the mechanics block "
                             f"(fields: {', '.join(coeffs)})")
        return InnerProduct(-grad(coeffs[p_name]), u)

    body.linear_in = p_name  # declared: the load is linear in the pressure field (B p)
    return body


def darcy_follower(p_name: str = "p", gamma=None):
    r"""The ``residual_density`` of :class:`~pacto_ng.physics.mechanics.Mechanics` for the
    Darcy pressure as a follower load (docs/theory.md §4).

    The body force ``b = -∇_x p`` acts in the deformed configuration; per unit reference
    volume it is ``b₀ = J b = -J F⁻ᵀ ∇_X p = -cof(F) ∇_X p`` with ``F = I + ∇u`` (``p`` is
    carried with the material points: it is the Darcy field of the reference design).  The
    external work is ``s t ∫ b₀·v dΩ₀``, so the returned density, *added to the residual*
    ``R = ∂Π/∂u + ...`` (internal minus external forces), is

        ``r(u, v) = -s b₀·v = s cof(F) ∇_X p · v``,

    which equals the fixed load's contribution (:func:`darcy_body`) at ``u = 0``.  Mechanics
    multiplies it by the thickness; ``s`` is its load-factor Parameter.

    The cofactor ``cof(F) = J F⁻ᵀ`` is used rather than ``det F · F⁻ᵀ``: it is polynomial in
    ``∇u`` (affine in 2D: ``cof(I + G) = I + cof(G)``; quadratic in 3D:
    ``cof(I + G) = I + (tr G I - Gᵀ) + cof(G)``), defined for every ``F`` (also where the
    fictitious void is inverted) and differentiated by NGSolve without a division.  Because it
    is affine in 2D, a *linear* material with this load still has a residual that is affine in
    ``u`` in 2D: one Newton step is exact.  In 3D it is not: the density declares
    ``affine_dims = (2,)``, and :class:`~pacto_ng.physics.mechanics.Mechanics` solves a linear
    material with it on a 3D mesh by Newton (with the tangent at the solution for the
    adjoint).  In plane stress (2D) the change of the out-of-plane thickness is not included
    in the load (the pressure acts on the reference thickness).

    ``gamma`` (a callable ``coeffs -> CF`` in [0, 1], e.g. the Wang interpolation factor
    :meth:`~pacto_ng.physics.wang.WangModel.gamma`): the load follows ``F_γ = I + γ∇u``, the
    deformation the Wang energy's large-strain part sees, instead of ``F``:
    ``cof(F_γ) = I + γ cof(∇u)`` in 2D.  In solid (γ = 1) this is the follower load; in void
    (γ = 0) it is the fixed load, as small-strain theory models the void (in 3D
    ``cof(F_γ)`` is quadratic in ``γ∇u``, with the same two limits).  Without it the
    load's own stiffness (of the order of the pressure) acts on void material whose stiffness
    is E0: once the pressure exceeds E0 by far, the fictitious void can buckle under its own
    load and Newton finds no equilibrium.

    Returns
    -------
    callable ``(u, v, coeffs, load) -> CF``
        ``load * cof(I + ∇u) ∇p · v`` with ``p = coeffs[p_name]`` (``γ∇u`` with ``gamma``).
    """
    def density(u, v, coeffs, load):
        from ngsolve import Cof, Grad, Id, InnerProduct, grad

        if p_name not in coeffs:
            raise ValueError(f"p_name: '{p_name}' is not a field of the mechanics block "
                             f"(fields: {', '.join(coeffs)})")
        G = Grad(u)
        if gamma is not None:
            G = gamma(coeffs) * G
        F = Id(G.dims[0]) + G
        return load * InnerProduct(Cof(F) * grad(coeffs[p_name]), v)

    density.affine_dims = (2,)  # declared: affine in u on 2D meshes only (see above)
    return density


class Compliance:
    r"""Compliance with the design-dependent load: block ``(u, p) -> J``.

    ``J = f(p)·u = t ∫ -∇p·u dΩ + Σ F_i·u_i`` (the Darcy load and any point/edge loads of the
    mechanics block, at unit load factor, as :func:`pacto_ng.responses.compliance`).  This is
    the (end) compliance of the *deformation-independent* load only: with a follower load the
    load vector depends on ``u`` and no compliance is defined (:func:`pacto_ng.case.build_problem`
    rejects that combination; use the strain energy or a mechanism objective).

    Backward: ``∂J/∂u`` and ``∂J/∂p`` (≠ 0: the load depends on the design through p) as
    LinearForms from ``Diff``; the ``p`` part flows back through
    :class:`~pacto_ng.physics.darcy.DarcyPressure`.

    Parameters
    ----------
    mech : Mechanics
        The mechanics block (its space, thickness, quadrature rule and point loads).
    pressure : ~pacto_ng.physics.darcy.DarcyPressure
        The pressure block (its space and output name).
    inputs : (str, str), optional
        Names of ``u`` and ``p`` (default: the two blocks' outputs).
    """

    def __init__(self, mech, pressure: DarcyPressure, inputs=None, output: str = "compliance"):
        from ngsolve import GridFunction, InnerProduct, LinearForm, grad

        self.mech, self.pressure = mech, pressure
        self.inputs = tuple(inputs) if inputs is not None else (mech.output, pressure.output)
        self.output = output
        self.gfu = GridFunction(mech.space)  # the state (the displacement, or u, ϑ, p̃)
        self.gfp = GridFunction(pressure.fes)
        u = mech.displacement(self.gfu)
        dens = mech.thickness * InnerProduct(-grad(self.gfp), u)
        self._dens = dens
        v = mech.displacement(mech.space.TestFunction())
        self._fixed = None  # the design-independent point/edge loads (assembled once)
        if mech.loads:
            lf = LinearForm(mech.space)
            for ld in mech.loads:
                lf += ld.work(mech.mesh, v)
            lf.Assemble()
            self._fixed = lf.vec
        self._du = LinearForm(mech.space)
        self._du += dens.Diff(u, v) * mech.DX
        self._dp = LinearForm(pressure.fes)
        self._dp += dens.Diff(self.gfp, pressure.fes.TestFunction()) * mech.DX

    def forward(self, u, p):
        from ngsolve import Integrate

        self.gfu.vec.data = u
        if isinstance(p, np.ndarray):
            self.gfp.vec.FV().NumPy()[:] = p
        else:
            self.gfp.vec.data = p
        val = total(self.mech.mesh, Integrate(self._dens * self.mech.DX, self.mech.mesh))
        if self._fixed is not None:
            val += float(self._fixed.InnerProduct(self.gfu.vec))
        return val

    def backward(self, g):
        g = float(g)
        self._du.Assemble()
        self._dp.Assemble()
        du = self._du.vec.CreateVector()
        du.data = g * self._du.vec
        if self._fixed is not None:
            du.data += g * self._fixed
        dp = self._dp.vec.CreateVector()
        dp.data = g * self._dp.vec
        return (du, dp)



def for_case(mesh, settings: DarcySettings, p_in: float, pressure, rho_name: str = "rho_bar", *,
             order: int = 1, output: str = "p", gamma=None, solver: str = "auto"):
    """Build the Darcy part of a case: ``(DarcyPressure block, Field for Mechanics, load)``.

    ``pressure`` has ``inlet`` and ``zero`` (boundary names); ``p_in`` is the inlet pressure.
    ``settings.load_type`` chooses the third item: ``"fixed"`` gives :func:`darcy_body`
    (``Mechanics(body=...)``), ``"follower"`` gives :func:`darcy_follower`
    (``Mechanics(residual_density=...)``), with ``gamma`` passed on to it.  ``solver``: the
    pressure system's route (``auto``, ``direct`` or ``iterative``,
    :class:`~pacto_ng.physics.solvers.LinearSolver`).
    """
    d = settings
    block = DarcyPressure(mesh, inlet=pressure.inlet, zero=pressure.zero, p_in=p_in,
                          order=order, Kv=d.Kv, Ks=d.Ks, eta_k=d.eta_k, beta_k=d.beta_k,
                          eta_h=d.eta_h, beta_h=d.beta_h, r=d.r, delta_s=d.delta_s,
                          p_out=d.p_out, sensitivity=d.load_sensitivity, inputs=(rho_name,),
                          output=output, solver=solver)
    load = darcy_body(output) if d.load_type == "fixed" else darcy_follower(output, gamma)
    return block, block.field(), load
