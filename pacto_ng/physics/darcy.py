r"""Design-dependent pressure by the Darcy–drainage method (SPEC §2, thesis ch. 3).

Every element is treated as a porous medium.  With the smoothed Heaviside
``H(ρ; η, β) = (tanh(βη) + tanh(β(ρ-η))) / (tanh(βη) + tanh(β(1-η)))``:

* flow coefficient (thesis eq. 3.2):  ``K(ρ̄) = Kv - (Kv - Ks) H(ρ̄; ηk, βk)``;
* drainage (thesis eqs 3.3–3.4):      ``D(ρ̄) = (ln r / Δs)² Ks H(ρ̄; ηh, βh)``,
  ``Q_drain = -D (p - p_out)``;
* pressure (thesis eqs 3.5–3.7): find ``p ∈ H1`` with

  ``∫ K ∇p·∇q + D p q dΩ = ∫ D p_out q dΩ``  for all ``q`` vanishing on the Dirichlet parts,

  ``p = P_in`` on the inlet boundaries, ``p = 0`` on the zero-pressure boundaries (a point
  shared by both gets 0), no flux elsewhere.  In a fully solid region ``-Ks p'' + D p = 0``
  gives ``p ∝ exp(-|ln r| x / Δs)``: the pressure falls to ``r P_in`` at depth ``Δs``.
* load (thesis eq. 3.8): body force ``b = -∇p``, external work ``t ∫ -∇p·u dΩ`` (``f = -H p``),
  deformation independent (SPEC §4).  :func:`darcy_body` gives it to
  :class:`~pacto_ng.physics.mechanics.Mechanics`, whose load factor multiplies it; the pressure
  is linear in ``(P_in, p_out)``, so the load factor scales the pressure itself.
* follower load (SPEC §4, beyond the thesis): the spatial body force ``-∇_x p`` acting on the
  deformed body, pulled back to the reference configuration, ``-J F⁻ᵀ ∇_X p`` per unit
  reference volume (:func:`darcy_follower`).  It has no potential: it is a residual term of
  :class:`~pacto_ng.physics.mechanics.Mechanics` with an unsymmetric tangent (the load
  stiffness) and enters the sensitivity through ``λᵀ ∂R/∂p``.

Sensitivities (discrete adjoint, backward pass of :class:`DarcyPressure`).  With the residual
``R(p, ρ̄) = A(ρ̄) p - f(ρ̄)`` on the free dofs and the Dirichlet values fixed,

    ``A λ = dJ/dp`` (free dofs, ``λ = 0`` on the Dirichlet dofs),
    ``dJ/dρ̄_e = -λᵀ ∂R/∂ρ̄_e = -∂/∂ρ̄_e ∫ K ∇p·∇λ + D (p - p_out) λ dΩ``,

where ``A`` is symmetric, so the transposed solve reuses the Cholesky factorisation of the
forward solve.  Because ρ̄ is constant on each element, so are ``K`` and ``D``: they are
evaluated in numpy and handed to NGSolve as L2-order-0 GridFunctions (no Heaviside CF at every
quadrature point), and the last term is ``-(K'(ρ̄_e) ∫_e ∇p·∇λ + D'(ρ̄_e) ∫_e (p - p_out) λ)``,
one LinearForm on the L2-order-0 space with the element-wise derivatives ``K'``, ``D'`` as
coefficients, integrated with the same quadrature rule as ``A`` (NGSOLVE_NOTES, "one quadrature
rule everywhere").
"""
from __future__ import annotations

import numpy as np

from dataclasses import dataclass

from ..interpolation import heaviside_deriv_np, heaviside_np
from ..params import InputError
from ..settings import Settings, setting
from .mechanics import Field
from .quadrature import integration_rules

__all__ = ["DarcySettings", "DarcyPressure", "darcy_body", "darcy_follower", "pressure_field", "Compliance",
           "DarcyCompliance", "for_case"]


@dataclass(frozen=True)
class DarcySettings(Settings):
    """The Darcy–drainage pressure model (SPEC §2, thesis Table 6.1) and its load."""

    Kv: float = setting(1.0, "m^2/(Pa s)", "flow coefficient of void", range="(0, inf)")
    Ks: float = setting(1e-7, "m^2/(Pa s)", "flow coefficient of solid", range="(0, inf)")
    eta_k: float = setting(0.3, "", "flow coefficient step threshold ηk", range="(0, 1)")
    beta_k: float = setting(10.0, "", "flow coefficient step sharpness βk", range="[0, 1e4]")
    eta_h: float = setting(0.2, "", "drainage step threshold ηh", range="(0, 1)")
    beta_h: float = setting(10.0, "", "drainage step sharpness βh", range="[0, 1e4]")
    r: float = setting(0.1, "", "pressure ratio reached at depth delta_s in solid",
                       range="(0, 1)")
    delta_s: float = setting(0.002, "m", "pressure penetration depth Δs", range="(0, inf)")
    p_out: float = setting(0.0, "Pa", "drainage outside pressure", range="[-1e300, 1e300]")
    load_type: str = setting("fixed", "", "Darcy load: fixed | follower",
                             choices=("fixed", "follower"))
    follower_wang: bool = setting(True, "", "Wang model: the follower load sees I + γ∇u "
                                  "(void: fixed load)")
    load_sensitivity: bool = setting(True, "", "include the pressure-load sensitivity (off: "
                                     "study only)")
    inlet: str = setting("", "", "Darcy inlet boundary name(s), '|'-separated (empty: the "
                         "case's own)")

    def check(self):
        if not self.Ks < self.Kv:
            raise InputError(f"Ks: must satisfy 0 < Ks < Kv (got Ks={self.Ks:g}, "
                             f"Kv={self.Kv:g})")


def _names(value, what: str) -> tuple[str, ...]:
    if isinstance(value, str):
        return (value,)
    try:
        names = tuple(value)
    except TypeError:
        raise ValueError(f"{what}: expected a boundary name or a sequence of names "
                         f"(got {value!r})") from None
    for n in names:
        if not isinstance(n, str):
            raise ValueError(f"{what}: boundary names must be strings (got {n!r})")
    return names


class DarcyPressure:
    r"""Block ``ρ̄ -> p``: the Darcy–drainage pressure field (thesis eqs 3.2–3.7).

    Parameters
    ----------
    mesh : ngsolve.Mesh
    inlet : str or sequence of str
        Boundary name(s) where ``p = P_in``.
    zero : str or sequence of str, optional
        Boundary name(s) where ``p = 0``.  May be empty (the inlet alone fixes the level).
    p_in : float
        Inlet pressure ``P_in`` (Pa), the load magnitude.  Mutable attribute.
    order : int
        Order of the H1 pressure space (use the displacement order).
    Kv, Ks : float
        Flow coefficients of void and solid, ``0 < Ks < Kv``; ``Ks = 1e-7 Kv`` by default
        (thesis Table 6.1).
    eta_k, beta_k, eta_h, beta_h : float
        Heaviside steps of the flow coefficient (thesis eq. 3.2) and of the drainage
        (thesis eq. 3.4); ``η ∈ (0, 1)``, ``β >= 0``.  Defaults 0.3, 10, 0.2, 10.
    r : float
        Pressure ratio reached at depth ``Δs`` in solid, ``0 < r < 1`` (default 0.1).
    delta_s : float
        Penetration depth ``Δs`` (m), positive (default 0.002).
    p_out : float
        Drainage (outside) pressure ``p_out`` (default 0).
    sensitivity : bool
        If False, :meth:`backward` returns a zero gradient: the load sensitivity (the whole
        ``dJ/dp`` path) is dropped.  For studies only; the gradient is then wrong.
    inputs, output : names in a :class:`~pacto_ng.core.Chain`.
    intorder : int, optional
        Order of the quadrature rule used by every form (default ``2 * order``: exact for
        ``A`` on element-wise constant densities, triangles and quads).
    inverse : str
        Sparse direct solver (always passed explicitly to NGSolve).

    Notes
    -----
    Forward: ``p = P_in ℓ + p0`` with the lifting ``ℓ`` (1 on the inlet dofs, 0 elsewhere) and
    ``A_ff p0 = f_f - (A P_in ℓ)_f``.  Backward: see the module docstring; ``grad_output`` may be a
    BaseVector on :attr:`fes` or a numpy array of its length.
    """

    def __init__(self, mesh, *, inlet, zero=(), p_in: float = 1.0, order: int = 1,
                 Kv: float = 1.0, Ks: float | None = None, eta_k: float = 0.3,
                 beta_k: float = 10.0, eta_h: float = 0.2, beta_h: float = 10.0,
                 r: float = 0.1, delta_s: float = 0.002, p_out: float = 0.0,
                 sensitivity: bool = True, inputs=("rho_bar",), output: str = "p",
                 intorder: int | None = None, inverse: str = "sparsecholesky"):
        from ngsolve import (BND, H1, L2, BilinearForm, GridFunction, LinearForm, dx, grad)

        inlet = _names(inlet, "inlet")
        zero = _names(zero, "zero")
        Ks = 1e-7 * Kv if Ks is None else Ks
        self._validate(mesh, inlet, zero, p_in, order, Kv, Ks, eta_k, beta_k, eta_h, beta_h,
                       r, delta_s, p_out)
        self.mesh, self.order = mesh, int(order)
        self.inlet, self.zero = inlet, zero
        self.p_in, self.p_out = float(p_in), float(p_out)
        self.Kv, self.Ks = float(Kv), float(Ks)
        self.eta_k, self.beta_k = float(eta_k), float(beta_k)
        self.eta_h, self.beta_h = float(eta_h), float(beta_h)
        self.r, self.delta_s = float(r), float(delta_s)
        self.sensitivity = bool(sensitivity)
        self.inputs, self.output = tuple(inputs), output
        if len(self.inputs) != 1:
            raise ValueError("inputs: DarcyPressure takes exactly one density field")
        self.inverse_type = inverse

        self.fes = H1(mesh, order=self.order, dirichlet="|".join(inlet + zero))
        self.l2 = L2(mesh, order=0)
        self.rules = integration_rules(intorder or 2 * self.order)
        DX = dx(intrules=self.rules)
        self.DX = DX
        self.rho = GridFunction(self.l2)
        # K(ρ̄) and D(ρ̄) are element-wise constants: computed in numpy in forward()
        self.K = GridFunction(self.l2)
        self.D = GridFunction(self.l2)
        self._dK = GridFunction(self.l2)
        self._dD = GridFunction(self.l2)
        self._drain = (np.log(self.r) / self.delta_s) ** 2 * self.Ks

        p, q = self.fes.TnT()
        self.a = BilinearForm(self.fes, symmetric=True)
        self.a += (self.K * grad(p) * grad(q) + self.D * p * q) * DX
        self.f = LinearForm(self.fes)
        self.f += self.D * self.p_out * q * DX
        self._inv = None

        # unit lifting: 1 on the inlet dofs, 0 elsewhere (zero-pressure dofs win at shared points)
        lift = GridFunction(self.fes)
        lift.Set(1.0, BND, definedon=mesh.Boundaries("|".join(inlet)))
        on_inlet = self.fes.GetDofs(mesh.Boundaries("|".join(inlet)))
        vals = lift.vec.FV().NumPy()
        vals[~np.array(list(on_inlet), dtype=bool)] = 0.0
        if zero:
            on_zero = np.array(list(self.fes.GetDofs(mesh.Boundaries("|".join(zero)))), dtype=bool)
            vals[on_zero] = 0.0
        self._lift = lift.vec

        # state, adjoint and the sensitivity form -λᵀ ∂R/∂ρ̄ (built once)
        self.gfp = GridFunction(self.fes)
        self.lam = GridFunction(self.fes)
        q0 = self.l2.TestFunction()
        self._sens = LinearForm(self.l2)
        self._sens += (self._dK * grad(self.gfp) * grad(self.lam)
                       + self._dD * (self.gfp - self.p_out) * self.lam) * q0 * DX
        self._rhs = self.gfp.vec.CreateVector()
        self._ready = False
        # A(ρ̄) = Σ_e K_e L_e + D_e M_e from precomputed element matrices (ElementMatrices),
        # built at the second design (a single analysis does not pay for them): a sparse
        # product per design instead of an assembly; the sensitivities from the same element
        # matrices.  None (then the forms are assembled) until then or if the check fails.
        self._scatter = None
        self._scatter_pending = True
        self._designs = 0
        one = GridFunction(self.fes)
        one.Set(1.0)
        self._one = one.vec.FV().NumPy().copy()  # the constant 1 (p - p_out in the sensitivity)

    # -- validation --------------------------------------------------------------------------
    @staticmethod
    def _validate(mesh, inlet, zero, p_in, order, Kv, Ks, eta_k, beta_k, eta_h, beta_h, r,
                  delta_s, p_out):
        known = sorted(set(mesh.GetBoundaries()))
        if not inlet:
            raise ValueError("inlet: at least one inlet boundary is needed")
        for what, names in (("inlet", inlet), ("zero", zero)):
            for n in names:
                if n not in known:
                    raise ValueError(f"{what}: boundary '{n}' is not in the mesh "
                                     f"(boundaries: {', '.join(known)})")
        both = sorted(set(inlet) & set(zero))
        if both:
            raise ValueError(f"zero: boundary {both} is also an inlet")
        if order not in (1, 2, 3, 4):
            raise ValueError(f"order: must be 1, 2, 3 or 4 (got {order})")
        if not np.isfinite(p_in):
            raise ValueError(f"p_in: must be finite (got {p_in})")
        # the model's parameters: checked by their declarations (one place)
        DarcySettings(Kv=float(Kv), Ks=float(Ks), eta_k=float(eta_k), beta_k=float(beta_k),
                      eta_h=float(eta_h), beta_h=float(beta_h), r=float(r),
                      delta_s=float(delta_s), p_out=float(p_out))

    # -- block interface ------------------------------------------------------------------------
    def forward(self, rho):
        """Solve ``A(ρ̄) p = f(ρ̄)`` with ``p = P_in`` on the inlet, 0 on the zero boundaries."""
        rho = np.asarray(rho, dtype=float)
        if rho.shape != (self.l2.ndof,):
            raise ValueError(f"{self.inputs[0]}: expected {self.l2.ndof} element values "
                             f"(got shape {rho.shape})")
        self.rho.vec.FV().NumPy()[:] = rho
        Kvals = self.Kv - (self.Kv - self.Ks) * heaviside_np(rho, self.eta_k, self.beta_k)
        Dvals = self._drain * heaviside_np(rho, self.eta_h, self.beta_h)
        if self._scatter_pending and self._designs >= 1:
            self._build_scatter()
        self._designs += 1
        self.K.vec.FV().NumPy()[:] = Kvals
        self.D.vec.FV().NumPy()[:] = Dvals
        if self._scatter is not None:
            self._scatter.assemble([Kvals, Dvals])
        else:
            self.a.Assemble()
        if self.p_out == 0.0:
            self.f.vec[:] = 0.0  # ∫ D p_out q = 0
        else:
            self.f.Assemble()
        if self._inv is None:
            self._inv = self.a.mat.Inverse(self.fes.FreeDofs(), inverse=self.inverse_type)
        else:
            self._inv.Update()
        p = self.gfp.vec
        p.data = self.p_in * self._lift
        self._rhs.data = self.f.vec - self.a.mat * p
        p.data += self._inv * self._rhs
        self._ready = True
        out = p.CreateVector()
        out.data = p
        return out

    def adjoint(self, dJdp):
        """``λ`` with ``A λ = dJ/dp`` on the free dofs, ``λ = 0`` on the Dirichlet dofs."""
        if not self._ready:
            raise RuntimeError("DarcyPressure.backward called before forward")
        if isinstance(dJdp, np.ndarray):
            self._rhs.FV().NumPy()[:] = dJdp
        else:
            self._rhs.data = dJdp
        lam = self._rhs.CreateVector()
        lam.data = self._inv * self._rhs  # A symmetric: the forward factorisation serves
        return lam

    def backward(self, grad_output):
        """``dJ/dρ̄ = -λᵀ ∂R/∂ρ̄`` (zero if :attr:`sensitivity` is off)."""
        if not self.sensitivity:
            return (np.zeros(self.l2.ndof),)
        self.lam.vec.data = self.adjoint(grad_output)
        rho = self.rho.vec.FV().NumPy()
        dK = -(self.Kv - self.Ks) * heaviside_deriv_np(rho, self.eta_k, self.beta_k)
        dD = self._drain * heaviside_deriv_np(rho, self.eta_h, self.beta_h)
        if self._scatter is not None:
            lam = self.lam.vec.FV().NumPy()
            p = self.gfp.vec.FV().NumPy()
            qK, qD = self._scatter.quadratic(lam, p)
            if self.p_out != 0.0:
                _, qD = self._scatter.quadratic(lam, p - self.p_out * self._one)
            return (-(dK * qK + dD * qD),)
        self._dK.vec.FV().NumPy()[:] = dK
        self._dD.vec.FV().NumPy()[:] = dD
        self._sens.Assemble()
        return (-self._sens.vec.FV().NumPy().copy(),)

    # -- helpers --------------------------------------------------------------------------------
    def _build_scatter(self):
        from .scatter import ElementMatrices

        def set_coefficients(cs):
            self.K.vec.FV().NumPy()[:] = cs[0]
            self.D.vec.FV().NumPy()[:] = cs[1]

        self._scatter_pending = False
        self._scatter = ElementMatrices.build(self.a, self.fes, set_coefficients, 2)

    def field(self) -> Field:
        """The :class:`~pacto_ng.physics.mechanics.Field` through which ``p`` enters Mechanics."""
        return Field(self.output, self.fes)

    def decay_rate(self) -> float:
        """``|ln r| / Δs``: the exponential decay rate of the pressure in solid (1/m)."""
        return abs(np.log(self.r)) / self.delta_s


def pressure_field(block: DarcyPressure) -> Field:
    """``Field(block.output, block.fes)`` for ``Mechanics(fields=(..., pressure_field(b)))``."""
    return block.field()


def darcy_body(p_name: str = "p"):
    r"""The ``body`` callable of :class:`~pacto_ng.physics.mechanics.Mechanics` for the Darcy load.

    Returns ``(u, coeffs) -> -∇p · u``: the body-force potential density of ``b = -∇p``
    (thesis eq. 3.8), deformation independent (SPEC §4).  Mechanics multiplies it by the
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
    Darcy pressure as a follower load (SPEC §4).

    The body force ``b = -∇_x p`` acts in the deformed configuration; per unit reference
    volume it is ``b₀ = J b = -J F⁻ᵀ ∇_X p = -cof(F) ∇_X p`` with ``F = I + ∇u`` (``p`` is
    carried with the material points: it is the Darcy field of the reference design).  The
    external work is ``s t ∫ b₀·v dΩ₀``, so the returned density, *added to the residual*
    ``R = ∂Π/∂u + ...`` (internal minus external forces), is

        ``r(u, v) = -s b₀·v = s cof(F) ∇_X p · v``,

    which equals the fixed load's contribution (:func:`darcy_body`) at ``u = 0``.  Mechanics
    multiplies it by the thickness; ``s`` is its load-factor Parameter.

    The cofactor ``cof(F) = J F⁻ᵀ`` is used rather than ``det F · F⁻ᵀ``: it is polynomial in
    ``∇u`` (affine in 2D: ``cof(I + G) = I + cof(G)``), defined for every ``F`` (also where the
    fictitious void is inverted) and differentiated by NGSolve without a division.  Because it
    is affine in 2D, a *linear* material with this load still has a residual that is affine in
    ``u``: one Newton step is exact.  In plane stress the change of the out-of-plane thickness
    is not included in the load (the pressure acts on the reference thickness).

    ``gamma`` (a callable ``coeffs -> CF`` in [0, 1], e.g. the Wang interpolation factor
    :meth:`~pacto_ng.physics.wang.WangModel.gamma`): the load follows ``F_γ = I + γ∇u``, the
    deformation the Wang energy's large-strain part sees, instead of ``F``:
    ``cof(F_γ) = I + γ cof(∇u)`` in 2D.  In solid (γ = 1) this is the follower load; in void
    (γ = 0) it is the fixed load, as small-strain theory models the void.  Without it the
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

    return density


class Compliance:
    r"""Compliance with the design-dependent load: block ``(u, p) -> J``.

    ``J = f(p)·u = t ∫ -∇p·u dΩ + Σ F_i·u_i`` (the Darcy load and any point/edge loads of the
    mechanics block, at unit load factor, as :func:`pacto_ng.responses.compliance`).  This is
    the (end) compliance of the *deformation-independent* load only: with a follower load the
    load vector depends on ``u`` and no compliance is defined (:func:`pacto_ng.case.build_problem`
    rejects that combination; use the strain energy or a mechanism objective).

    Backward: ``∂J/∂u`` and ``∂J/∂p`` (≠ 0: the load depends on the design through p) as
    LinearForms from ``Diff``; the ``p`` part flows back through :class:`DarcyPressure`.

    Parameters
    ----------
    mech : Mechanics
        The mechanics block (its space, thickness, quadrature rule and point loads).
    pressure : DarcyPressure
        The pressure block (its space and output name).
    inputs : (str, str), optional
        Names of ``u`` and ``p`` (default: the two blocks' outputs).
    """

    def __init__(self, mech, pressure: DarcyPressure, inputs=None, output: str = "compliance"):
        from ngsolve import GridFunction, InnerProduct, LinearForm, grad

        self.mech, self.pressure = mech, pressure
        self.inputs = tuple(inputs) if inputs is not None else (mech.output, pressure.output)
        self.output = output
        self.gfu = GridFunction(mech.fes)
        self.gfp = GridFunction(pressure.fes)
        dens = mech.thickness * InnerProduct(-grad(self.gfp), self.gfu)
        self._dens = dens
        v = mech.fes.TestFunction()
        self._fixed = None  # the design-independent point/edge loads (assembled once)
        if mech.loads:
            lf = LinearForm(mech.fes)
            for ld in mech.loads:
                lf += ld.work(mech.mesh, v)
            lf.Assemble()
            self._fixed = lf.vec
        self._du = LinearForm(mech.fes)
        self._du += dens.Diff(self.gfu, v) * mech.DX
        self._dp = LinearForm(pressure.fes)
        self._dp += dens.Diff(self.gfp, pressure.fes.TestFunction()) * mech.DX

    def forward(self, u, p):
        from ngsolve import Integrate

        self.gfu.vec.data = u
        if isinstance(p, np.ndarray):
            self.gfp.vec.FV().NumPy()[:] = p
        else:
            self.gfp.vec.data = p
        val = float(Integrate(self._dens * self.mech.DX, self.mech.mesh))
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


DarcyCompliance = Compliance


def for_case(mesh, settings: DarcySettings, p_in: float, pressure, rho_name: str = "rho_bar", *,
             order: int = 1, output: str = "p", gamma=None):
    """Build the Darcy part of a case: ``(DarcyPressure block, Field for Mechanics, load)``.

    ``pressure`` has ``inlet`` and ``zero`` (boundary names); ``p_in`` is the inlet pressure.
    ``settings.load_type`` chooses the third item: ``"fixed"`` gives :func:`darcy_body`
    (``Mechanics(body=...)``), ``"follower"`` gives :func:`darcy_follower`
    (``Mechanics(residual_density=...)``), with ``gamma`` passed on to it.
    """
    d = settings
    block = DarcyPressure(mesh, inlet=pressure.inlet, zero=pressure.zero, p_in=p_in,
                          order=order, Kv=d.Kv, Ks=d.Ks, eta_k=d.eta_k, beta_k=d.beta_k,
                          eta_h=d.eta_h, beta_h=d.beta_h, r=d.r, delta_s=d.delta_s,
                          p_out=d.p_out, sensitivity=d.load_sensitivity, inputs=(rho_name,),
                          output=output)
    load = darcy_body(output) if d.load_type == "fixed" else darcy_follower(output, gamma)
    return block, block.field(), load


def leakage(block: DarcyPressure, rho, h: float, *, solid: float = 0.9, void: float = 0.5,
            skin: float | None = None) -> dict:
    r"""How much pressure reaches solid material away from the pressurised cavity.

    Definitions (element densities ``ρ̄`` as given to ``block``; vertex pressures ``p``):

    * **cavity**: the elements with ``ρ̄ < void`` (0.5) that are connected to the inlet
      boundary through elements with ``ρ̄ < void`` sharing a vertex (an element touching the
      inlet with a vertex starts the search; vertex neighbours because the discrete pressure
      passes through shared vertices);
    * **wet skin**: the elements whose centroid lies within ``skin`` of a vertex of the cavity
      or of the inlet boundary.  Default ``skin = h + 2 max(Δs, h)``: one transition element
      plus the depth at which the solid has brought the pressure down to about 1 %: ``2 Δs``
      for the exact decay ``exp(-|ln r| x / Δs)`` (``r² = 1 %``, SPEC §2), but two elements on
      meshes coarser than the decay length ``Δs / |ln r|``, where the P1 solution falls only by
      a factor of about 0.16–0.2 per element (0.16 at h = 2 Δs, the thesis mesh).  In this
      skin the pressure is expected to drop, not leaked;
    * **outside the cavity**: the elements with ``ρ̄ >= solid`` (0.9) that are not in the skin.

    The leakage is the largest element pressure (the mean of its vertex values) found outside
    the cavity, as a fraction of ``P_in``; 0 if there is no such element.  ``leakage_any`` is
    the same maximum over *every* element that is neither in the cavity nor in the skin (also
    void pockets the pressure reached through a wall, and grey material): the stricter figure.

    Returns a dict: ``leakage``, ``where`` (centroid of that element, or None),
    ``leakage_any``, ``where_any``, ``skin``, ``elements_checked``, ``cavity_elements``.
    """
    from ngsolve import BND
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    mesh = block.mesh
    rho = np.asarray(rho, dtype=float)
    skin = h + 2.0 * max(block.delta_s, h) if skin is None else float(skin)
    pts = np.array([v.point for v in mesh.vertices])
    conn = [[v.nr for v in el.vertices] for el in mesh.Elements()]
    rows = np.repeat(np.arange(len(conn)), [len(c) for c in conn])
    cols = np.concatenate(conn)
    inc = csr_matrix((np.ones(rows.size), (rows, cols)), shape=(len(conn), mesh.nv))
    inlet_v = np.zeros(mesh.nv, dtype=bool)
    for el in mesh.Elements(BND):
        if el.mat in block.inlet:
            inlet_v[[v.nr for v in el.vertices]] = True
    # cavity: components of the low-density elements (vertex adjacency) that touch the inlet
    low = np.flatnonzero(rho < void)
    cavity = np.zeros(len(conn), dtype=bool)
    if low.size:
        sub = inc[low]
        ncomp, label = connected_components(sub @ sub.T, directed=False)
        touching = np.unique(label[np.asarray(sub @ inlet_v.astype(float)).ravel() > 0])
        cavity[low[np.isin(label, touching)]] = True
    wet_v = inlet_v | (np.asarray(inc[cavity].sum(axis=0)).ravel() > 0)
    centroids = np.asarray(inc @ pts) / np.asarray(inc.sum(axis=1))
    dist = cKDTree(pts[wet_v]).query(centroids)[0]
    beyond = ~cavity & (dist > skin)
    outside = beyond & (rho >= solid)
    pv = block.gfp.vec.FV().NumPy()[:mesh.nv]
    pe = np.asarray(inc @ pv).ravel() / np.asarray(inc.sum(axis=1)).ravel()
    out = dict(leakage=0.0, where=None, leakage_any=0.0, where_any=None, skin=skin,
               elements_checked=int(outside.sum()), cavity_elements=int(cavity.sum()))
    for key, sel in (("", outside), ("_any", beyond)):
        if sel.any() and block.p_in != 0:
            k = np.flatnonzero(sel)[np.argmax(pe[sel])]
            out["leakage" + key] = float(max(pe[k], 0.0) / block.p_in)
            out["where" + key] = [float(c) for c in centroids[k][:2]]
    return out
