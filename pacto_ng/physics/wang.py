"""The Wang interpolation of a hyperelastic energy with the linear one (thesis ch. 5).

Wang, Lazarov, Sigmund and Jensen (2014) model void with small-strain theory and solid with
finite-strain theory, so that the crushed void elements of a large-displacement optimisation
do not stop Newton.  With ``G = ∇u`` and an element-wise interpolation factor ``γ``
(thesis eq. 5.1, docs/theory.md §3)

    φ_W(G) = φ_H(γ G) - φ_L(γ G) + φ_L(G),

where ``φ_H`` is a hyperelastic energy (Neo-Hookean, thesis eq. 4.4, by default; St
Venant–Kirchhoff, Mooney–Rivlin, Yeoh or Ogden possible, :data:`HYPERELASTIC`, or a preset's
law, :mod:`~pacto_ng.physics.presets`) and ``φ_L`` the linear energy (thesis eqs 2.11–2.12), both with the
SIMP modulus ``E(ρ̄)``, in the dimension of the mesh (3D, or 2D with its ``plane`` setting,
:mod:`~pacto_ng.physics.materials`).  ``γ = 0`` gives ``φ_L(G)`` exactly
(``φ_H(0) = φ_L(0) = 0``), ``γ = 1`` gives ``φ_H(G)`` exactly.  The interpolation factor is (thesis eq. 5.2)

    γ = H(ρ̄^p; η1, β1) = (tanh(β1 η1) + tanh(β1 (ρ̄^p - η1))) / (tanh(β1 η1) + tanh(β1 (1 - η1))),

a CoefficientFunction of the element density, so that the adjoint ``(φ_W).Diff(ρ̄)``
differentiates through it.  Defaults β1 = 100, η1 = 0.001 (thesis App. D); Wang et al. used
β1 = 500, η1 = 0.01.

The logarithm of the Neo-Hookean energy sees the deformation ``I + γ G``: the Newton guard is
``det(I + γ G) > 0`` (:meth:`WangModel.guard`) at the quadrature points, where the energy is
evaluated (declared in :attr:`WangModel.traits`); in void (``γ = 0``) any ``det(I + G)`` is
admissible, and an element folded at a corner is not refused.

Output measures (thesis eqs 5.3–5.5), all from the same ``G``:

* ``E_W1 = E_GL(γG) - ε(γG) + ε(G) = ε(G) + γ² ½ GᵀG`` (eq. 5.4),
* ``E_W2 = ε(G) + γ ½ GᵀG`` (eq. 5.5),
* ``S = S_H(γG) - S_L(γG) + S_L(G)`` (eq. 5.3 as evaluated in thesis App. E.2): each part the
  second Piola–Kirchhoff stress of its own energy at its own argument, ``S_H = F_γ⁻¹ ∂φ_H/∂F``
  and ``S_L = ∂φ_L/∂ε``, both by ``.Diff``.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from ..interpolation import heaviside_cf, power_cf
from .gradient import PLANES, dimension
from .hyperelastic import LAWS, Law
from .materials import first_piola_kirchhoff, linear_energy, neohookean_energy, svk_energy
from .presets import DEFAULT_SHAPES
from .traits import EnergyTraits


def _rubber():
    """Mooney–Rivlin, Yeoh and Ogden with their default shapes (the isochoric Neo-Hookean;
    :class:`~pacto_ng.physics.hyperelastic.Law` instances carry a preset's), all needing J > 0."""
    return {name: (Law(name, DEFAULT_SHAPES[name]), True) for name in LAWS}


#: the hyperelastic energies φ_H by name, and whether each needs det(I + γG) > 0
HYPERELASTIC = {"neohookean": (neohookean_energy, True), "gnl": (svk_energy, False),
                **_rubber()}


def wang_gamma_cf(rho, penal=3.0, beta: float = 100.0, eta: float = 0.001):
    """Interpolation factor ``γ = H(ρ̄^p; η1, β1)`` (thesis eq. 5.2) as a CoefficientFunction.

    ``penal`` may be an ngsolve ``Parameter`` (SIMP continuation); ``beta``/``eta`` are floats or
    Parameters.  ``H(0) = 0`` and ``H(1) = 1`` to round-off (1e-16).  ``ρ^p`` is
    :func:`~pacto_ng.interpolation.power_cf` (a plain ``ρ**p`` makes the residual NaN at ρ = 0).
    """
    return heaviside_cf(power_cf(rho, penal), eta, beta)


def wang_energy(G, E, nu, gamma, plane: str = "strain", hyper: str | Callable = "neohookean"):
    """``φ_W = φ_H(γG) - φ_L(γG) + φ_L(G)`` (thesis eq. 5.1) for a given ``γ`` (a CF).

    ``hyper`` names a hyperelastic model (``neohookean``, ``gnl``, ``mooney_rivlin``, ``yeoh``,
    ``ogden``: :data:`HYPERELASTIC`) or is a callable ``(G, E, nu, plane) -> CF``, e.g. a
    :class:`~pacto_ng.physics.hyperelastic.Law` with a preset's shape.
    """
    phi_h = _hyper(hyper)[0]
    gG = gamma * G
    return (phi_h(gG, E, nu, plane) - linear_energy(gG, E, nu, plane)
            + linear_energy(G, E, nu, plane))


def _hyper(hyper):
    if callable(hyper):
        return hyper, True
    try:
        return HYPERELASTIC[hyper]
    except KeyError:
        raise ValueError(f"unknown hyperelastic model '{hyper}' for the Wang interpolation "
                         f"(choose from {', '.join(HYPERELASTIC)})") from None


def _sym(A):
    return 0.5 * (A + A.trans)


@dataclass(frozen=True)
class WangModel:
    """The Wang interpolation of one hyperelastic model, as the energy/guard pair
    :class:`~pacto_ng.physics.mechanics.Mechanics` takes, plus output measures.

    ``energy, guard = model`` unpacks it.  Every method takes ``G`` (a d x d CF, ``∇u``; 2D or
    3D) and ``coeffs`` (field name -> GridFunction, as Mechanics passes them).

    Parameters
    ----------
    modulus : callable ``coeffs -> CF``
        Young's modulus, e.g. SIMP ``E0 + ρ̄^p (E1 - E0)``.
    nu : float
        Poisson's ratio.
    plane : {"strain", "stress"}
        2D meshes only; on a 3D mesh ``"stress"`` raises ``ValueError`` when the energy is
        built and ``"strain"`` changes nothing.
    field : str
        Name of the physical density ``ρ̄`` in ``coeffs``.
    penal : float or Parameter
        SIMP exponent ``p`` in ``γ = H(ρ̄^p)``.
    beta, eta : float or Parameter
        ``β1``, ``η1`` of eq. 5.2.
    hyper : str or callable
        The large-strain energy ``φ_H`` (default Neo-Hookean).
    gamma_fn : callable ``coeffs -> CF`` or None
        Replaces eq. 5.2 by a prescribed ``γ`` (fixed patterns such as the C-beam's, or tests).
    reads : tuple of str or None
        The fields ``modulus`` and ``γ`` read (None: not declared, any field); part of
        :attr:`traits`.
    """

    modulus: Callable
    nu: float
    plane: str = "strain"
    field: str = "rho_bar"
    penal: object = 3.0
    beta: object = 100.0
    eta: object = 0.001
    hyper: object = "neohookean"
    gamma_fn: Callable | None = None
    reads: tuple[str, ...] | None = None

    def __post_init__(self):
        _hyper(self.hyper)
        if self.plane not in PLANES:
            raise ValueError(f"plane must be 'strain' or 'stress' (got '{self.plane}')")
        if isinstance(self.beta, (int, float)) and self.beta < 0:
            raise ValueError("wang beta must be >= 0")
        if isinstance(self.eta, (int, float)) and not 0.0 <= self.eta < 1.0:
            raise ValueError("wang eta must lie in [0, 1)")

    # -- the model -------------------------------------------------------------------------
    def gamma(self, coeffs):
        """``γ`` (eq. 5.2, or ``gamma_fn``)."""
        if self.gamma_fn is not None:
            return self.gamma_fn(coeffs)
        return wang_gamma_cf(coeffs[self.field], self.penal, self.beta, self.eta)

    def energy(self, G, coeffs):
        """``φ_W(G)`` (eq. 5.1) per unit reference volume."""
        return wang_energy(G, self.modulus(coeffs), self.nu, self.gamma(coeffs), self.plane,
                           self.hyper)

    def jacobian(self, G, coeffs):
        """``det(I + γ G)``: the deformation whose logarithm enters ``φ_H(γG)``."""
        from ngsolve import Det, Id

        return Det(Id(dimension(G)) + self.gamma(coeffs) * G)

    @property
    def guard(self):
        """The Newton guard ``(G, coeffs) -> det(I + γG)`` (None if ``φ_H`` accepts any F)."""
        return self.jacobian if _hyper(self.hyper)[1] else None

    @property
    def traits(self):
        """The energy's declaration (:class:`~pacto_ng.physics.traits.EnergyTraits`): the fields
        it reads; stress-free at ``G = 0`` for a named ``φ_H`` (``∂φ_W/∂G = γ P_H(0) - γ σ_L(0)
        + σ_L(0) = 0``); not quadratic (the general route); its guard holds at the quadrature
        points, the only points where ``φ_H(γG)`` is evaluated."""
        # every named φ_H and every rubber Law is stress-free at G = 0 (P_H(0) = 0)
        named = isinstance(self.hyper, (str, Law))
        return EnergyTraits(reads=self.reads, stress_free=named, guard_points="quadrature")

    def mixed_energy(self, G, theta, p, coeffs, mixed):
        """The model in the mixed formulation (:class:`~pacto_ng.physics.mixed.Mixed`): the
        element dilatation ``Θ`` and pressure ``p̃`` act on the large-strain part's deformation
        ``F_γ = I + γG`` alone,

            φ_H(F̄_γ - I) - φ_L(γG) + φ_L(G) + p̃ (det F_γ - Θ),  F̄_γ = (Θ / det F_γ)^(1/d) F_γ,

        so that solid (``γ = 1``) is the mixed hyperelastic model and void (``γ = 0``, where
        ``Θ = 1``) the linear energy with any ``det(I + G)``, as in the displacement
        formulation."""
        E, nu, plane = self.modulus(coeffs), self.nu, self.plane
        gG = self.gamma(coeffs) * G
        Gbar, Jg, Theta = mixed.deformation(gG, theta)
        return (_hyper(self.hyper)[0](Gbar, E, nu, plane) - linear_energy(gG, E, nu, plane)
                + linear_energy(G, E, nu, plane) + p * (Jg - Theta))

    def mixed_guard(self, G, theta, coeffs, mixed):
        """The guard in the mixed formulation: ``Θ > 0`` and ``det(I + γG) > 0`` (positive where
        admissible)."""
        from ngsolve import IfPos

        _, Jg, Theta = mixed.deformation(self.gamma(coeffs) * G, theta)
        return IfPos(Theta, Jg, Theta)

    def __call__(self, G, coeffs):
        """The model as an energy density ``(G, coeffs) -> CF`` (same as :meth:`energy`)."""
        return self.energy(G, coeffs)

    def __iter__(self):
        yield self.energy
        yield self.guard

    # -- output measures ---------------------------------------------------------------------
    def strain_w1(self, G, coeffs):
        """``E_W1 = E_GL(γG) - ε(γG) + ε(G)`` (eq. 5.4): nonlinear part scaled by ``γ²``."""
        from ngsolve import Id

        d = dimension(G)
        gG = self.gamma(coeffs) * G
        Fg = Id(d) + gG
        egl = 0.5 * (Fg.trans * Fg - Id(d))
        return egl - _sym(gG) + _sym(G)

    def strain_w2(self, G, coeffs):
        """``E_W2 = ε(G) + γ ½ GᵀG`` (eq. 5.5): nonlinear part scaled by ``γ``."""
        return _sym(G) + self.gamma(coeffs) * (0.5 * (G.trans * G))

    def stress(self, G, coeffs):
        """``S = S_H(γG) - S_L(γG) + S_L(G)`` (eq. 5.3, App. E.2), d x d (in-plane in 2D).

        ``S_H(A) = (I + A)⁻¹ ∂φ_H/∂A`` and ``S_L(A) = ∂φ_L/∂A = λ tr ε I + 2μ ε``, both from
        ``.Diff`` of the energies.
        """
        from ngsolve import Id, Inv

        E, nu, plane = self.modulus(coeffs), self.nu, self.plane
        phi_h = _hyper(self.hyper)[0]
        gG = self.gamma(coeffs) * G
        s_h = Inv(Id(dimension(G)) + gG) * first_piola_kirchhoff(
            lambda A: phi_h(A, E, nu, plane), gG)
        s_l = lambda A: first_piola_kirchhoff(lambda B: linear_energy(B, E, nu, plane), A)
        return s_h - s_l(gG) + s_l(G)


def wang_model(modulus: Callable, nu: float, plane: str = "strain", field: str = "rho_bar",
               penal=3.0, *, beta=100.0, eta=0.001, hyper="neohookean",
               gamma_fn: Callable | None = None, reads=None) -> WangModel:
    """Factory of the Wang model; ``energy, guard = wang_model(...)`` (see :class:`WangModel`)."""
    return WangModel(modulus, nu, plane, field, penal, beta, eta, hyper, gamma_fn,
                     None if reads is None else tuple(reads))
