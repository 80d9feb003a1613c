r"""Design-dependent pressure by the Darcy–drainage method (docs/theory.md §2, thesis ch. 3).

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

The load this pressure puts on the mechanics block (fixed or follower) and the compliance of
that load are in :mod:`pacto_ng.physics.darcy_load`; the leakage figure of a solved pressure
field in :mod:`pacto_ng.physics.darcy_leakage`.

Sensitivities (discrete adjoint, backward pass of :class:`DarcyPressure`).  With the residual
``R(p, ρ̄) = A(ρ̄) p - f(ρ̄)`` on the free dofs and the Dirichlet values fixed,

    ``A λ = dJ/dp`` (free dofs, ``λ = 0`` on the Dirichlet dofs),
    ``dJ/dρ̄_e = -λᵀ ∂R/∂ρ̄_e = -∂/∂ρ̄_e ∫ K ∇p·∇λ + D (p - p_out) λ dΩ``,

where ``A`` is symmetric, so the transposed solve reuses the Cholesky factorisation of the
forward solve.  Because ρ̄ is constant on each element, so are ``K`` and ``D``: they are
evaluated in numpy and handed to NGSolve as L2-order-0 GridFunctions (no Heaviside CF at every
quadrature point), and the last term is ``-(K'(ρ̄_e) ∫_e ∇p·∇λ + D'(ρ̄_e) ∫_e (p - p_out) λ)``,
one LinearForm on the L2-order-0 space with the element-wise derivatives ``K'``, ``D'`` as
coefficients, integrated with the same quadrature rule as ``A`` (one rule everywhere: the
derivative is then that of the discrete functional, to round-off).
"""
from __future__ import annotations

import numpy as np

from dataclasses import dataclass

from ..errors import InputError
from ..interpolation import heaviside_deriv_np, heaviside_np
from ..settings import Settings, setting
from .mechanics import Field
from .quadrature import integration_rules
from .scatter import ElementMatrices
from .solvers import LinearSolver

__all__ = ["DarcySettings", "DarcyPressure"]


@dataclass(frozen=True)
class DarcySettings(Settings):
    """The Darcy–drainage pressure model (docs/theory.md §2, thesis Table 6.1) and its load."""

    Kv: float = setting(1.0, "m^2/(Pa s)", "flow coefficient of void", range="[1e-30, 1e30]")
    Ks: float = setting(1e-7, "m^2/(Pa s)", "flow coefficient of solid", range="[1e-30, 1e30]")
    eta_k: float = setting(0.3, "", "flow coefficient step threshold ηk", range="(0, 1)")
    beta_k: float = setting(10.0, "", "flow coefficient step sharpness βk", range="[0, 1e4]")
    eta_h: float = setting(0.2, "", "drainage step threshold ηh", range="(0, 1)")
    beta_h: float = setting(10.0, "", "drainage step sharpness βh", range="[0, 1e4]")
    r: float = setting(0.1, "", "pressure ratio reached at depth delta_s in solid",
                       range="(0, 1)")
    delta_s: float = setting(0.002, "m", "pressure penetration depth Δs", range="(0, 1e9]")
    p_out: float = setting(0.0, "Pa", "drainage outside pressure (its size below the inlet "
                           "pressure, the load)", range="[-1e30, 1e30]")
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
    solver : str
        ``auto``, ``direct`` or ``iterative``: the route of the pressure system
        (:class:`~pacto_ng.physics.solvers.LinearSolver`; :attr:`solver_info`).  On the
        iterative route the matrix is assembled by its form at every design (its
        preconditioner is built during the assembly), not from element matrices.

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
                 intorder: int | None = None, inverse: str = "sparsecholesky",
                 solver: str = "auto"):
        from ngsolve import H1, L2, BilinearForm, GridFunction, LinearForm, dx, grad

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
        self._solver = LinearSolver(self.a, self.fes.FreeDofs(), setting=solver,
                                    order=self.order, inverse=inverse, coarse=())  # no ds term

        self._lift = self._inlet_lifting()
        self._start_state()
        self._rhs = self.gfp.vec.CreateVector()
        self._dp = self.gfp.vec.CreateVector()
        self._ready = False
        # A(ρ̄) = Σ_e K_e L_e + D_e M_e from precomputed element matrices (ElementMatrices),
        # built at the second design (a single analysis does not pay for them), or at the
        # first after expect_many_designs: a sparse product per design instead of an assembly;
        # the sensitivities from the same element matrices.  None (then the forms are
        # assembled) until then or if the check fails.
        self._scatter = None
        self._scatter_pending = True
        self._designs = 0
        self._many_designs = False
        one = GridFunction(self.fes)
        one.Set(1.0)
        self._one = one.vec.FV().NumPy().copy()  # the constant 1 (p - p_out in the sensitivity)

    def _inlet_lifting(self):
        """The unit lifting ``ℓ``: 1 on the inlet dofs, 0 elsewhere (zero-pressure dofs win at
        shared points), a vector on :attr:`fes`."""
        from ngsolve import BND, GridFunction

        mesh, inlet, zero = self.mesh, self.inlet, self.zero
        lift = GridFunction(self.fes)
        lift.Set(1.0, BND, definedon=mesh.Boundaries("|".join(inlet)))
        on_inlet = self.fes.GetDofs(mesh.Boundaries("|".join(inlet)))
        vals = lift.vec.FV().NumPy()
        vals[~np.array(list(on_inlet), dtype=bool)] = 0.0
        if zero:
            on_zero = np.array(list(self.fes.GetDofs(mesh.Boundaries("|".join(zero)))), dtype=bool)
            vals[on_zero] = 0.0
        return lift.vec

    def _start_state(self):
        """The state :attr:`gfp`, the adjoint :attr:`lam` and the sensitivity form
        ``-λᵀ ∂R/∂ρ̄`` on them (built once)."""
        from ngsolve import GridFunction, LinearForm, grad

        self.gfp = GridFunction(self.fes)
        self.lam = GridFunction(self.fes)
        q0 = self.l2.TestFunction()
        self._sens = LinearForm(self.l2)
        self._sens += (self._dK * grad(self.gfp) * grad(self.lam)
                       + self._dD * (self.gfp - self.p_out) * self.lam) * q0 * self.DX

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
        Kvals, Dvals, _, _ = self.coefficients(rho)
        if (self._scatter_pending and self._solver.direct
                and (self._designs >= 1 or self._many_designs)):
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
        self._solver.prepare()
        p = self.gfp.vec
        p.data = self.p_in * self._lift
        self._rhs.data = self.f.vec - self.a.mat * p
        self._solver.solve(self._rhs, self._dp)
        p.data += self._dp
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
        self._solver.solve(self._rhs, lam)  # A symmetric: the forward factorisation serves
        return lam

    def backward(self, grad_output):
        """``dJ/dρ̄ = -λᵀ ∂R/∂ρ̄`` (zero if :attr:`sensitivity` is off)."""
        if not self.sensitivity:
            return (np.zeros(self.l2.ndof),)
        self.lam.vec.data = self.adjoint(grad_output)
        _, _, dK, dD = self.coefficients(self.rho.vec.FV().NumPy())
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

    def coefficients(self, rho):
        """``(K, D, dK/dρ̄, dD/dρ̄)`` per element: the flow coefficient
        ``K = Kv - (Kv - Ks) H(ρ̄; ηk, βk)`` and the drainage ``D = Ds H(ρ̄; ηh, βh)``."""
        hk, hd = (heaviside_np(rho, self.eta_k, self.beta_k),
                  heaviside_np(rho, self.eta_h, self.beta_h))
        return (self.Kv - (self.Kv - self.Ks) * hk, self._drain * hd,
                -(self.Kv - self.Ks) * heaviside_deriv_np(rho, self.eta_k, self.beta_k),
                self._drain * heaviside_deriv_np(rho, self.eta_h, self.beta_h))

    @property
    def pressure(self):
        """The pressure of the last forward pass, a GridFunction: the block's output, for
        evaluating and copying; the block sets it."""
        return self.gfp

    @property
    def solver_info(self) -> dict:
        """The pressure system's linear solver, for the run summary
        (:attr:`~pacto_ng.physics.solvers.LinearSolver.info`)."""
        return self._solver.info

    @property
    def route(self) -> str:
        """How the matrix of a design is assembled: ``"element_matrices"`` once they are built,
        else ``"forms"`` (NGSolve's assembly of the bilinear form)."""
        return "element_matrices" if self._scatter is not None else "forms"

    def expect_many_designs(self):
        """Say that many designs follow (an optimisation): the element matrices are built at
        the next design, not at the second.  Every design of a run then takes one route,
        whichever design its process starts at (a resumed run repeats the uninterrupted one
        bit for bit)."""
        self._many_designs = True

    # -- helpers --------------------------------------------------------------------------------
    def _build_scatter(self):
        def set_coefficients(cs):
            self.K.vec.FV().NumPy()[:] = cs[0]
            self.D.vec.FV().NumPy()[:] = cs[1]

        self._scatter_pending = False
        self._scatter = ElementMatrices.build(self.a, self.fes, set_coefficients, 2)

    def field(self) -> Field:
        """The :class:`~pacto_ng.physics.mechanics.Field` through which ``p`` enters Mechanics."""
        return Field(self.output, self.fes)
