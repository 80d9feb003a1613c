"""Strain-energy densities φ(∇u; E, ν) as NGSolve CoefficientFunctions (docs/theory.md §3).

Every model is a pure function of the displacement gradient ``G = ∇u`` (a d x d CF; the
dimension ``d = G.dims[0]`` is the mesh's), the Young's modulus ``E`` (a CF, e.g. SIMP of the
density) and Poisson's ratio ``ν``.  The residual and tangent come from ``Variation`` — nothing
is differentiated by hand.

* 3D (``d = 3``): the full three-dimensional energies with the Lamé constants of :func:`lame`.
  ``plane`` does not apply: ``"strain"`` (the default) is accepted and changes nothing,
  ``"stress"`` raises ``ValueError`` (a solid has no plane-stress state).
* 2D (``d = 2``): ``plane="strain"`` embeds ``F`` in 3x3 with ``F33 = 1``.  Plane stress uses
  the reduced Lamé constant ``λ* = 2λμ/(λ+2μ)`` for the quadratic models (exact for linear
  elasticity; the usual plane-stress St Venant–Kirchhoff).

| name | φ |
|---|---|
| ``linear`` | ``λ/2 tr(ε)² + μ ε:ε`` (thesis eqs 2.11–2.12) |
| ``gnl`` | St Venant–Kirchhoff ``λ/2 tr(E)² + μ E:E`` on Green–Lagrange ``E`` |
| ``neohookean`` | ``μ/2 (I1 - 3) - μ ln J + λ/2 (ln J)²`` (thesis eq. 4.4) |

Neo-Hookean in plane stress keeps the 3-D Lamé constants and finds the out-of-plane stretch
``F33 = c`` from ``S33 = 0`` at every integration point (:func:`plane_stress_stretch`): a
converged local Newton iteration, unrolled in CF form and frozen, followed by one
differentiable Newton correction, so that the energy, its gradient and its Hessian are those of
the exact reduced energy ``ψ(F) = min_c φ(F, c)``.

Stresses for output come from ``.Diff`` of the energy (:func:`first_piola_kirchhoff`,
:func:`second_piola_kirchhoff`), never from hand-written formulas.
"""
from __future__ import annotations

from dataclasses import dataclass

from .gradient import dimension
from .hyperelastic import LAWS, Law
from .presets import DEFAULT_SHAPES


def lame(E, nu, plane: str = "strain"):
    """Lamé constants (μ, λ); ``plane="stress"`` returns the reduced λ* (2D only: the energies
    check the dimension, :func:`~pacto_ng.physics.gradient.dimension`)."""
    mu = E / (2.0 * (1.0 + nu))
    lam = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))
    if plane == "stress":
        lam = 2.0 * lam * mu / (lam + 2.0 * mu)
    return mu, lam


def linear_energy(G, E, nu, plane="strain"):
    """Small-strain energy ``λ/2 tr(ε)² + μ ε:ε`` with ``ε = sym G`` (2D or 3D)."""
    from ngsolve import InnerProduct, Trace

    dimension(G, plane)
    mu, lam = lame(E, nu, plane)
    eps = 0.5 * (G + G.trans)
    return 0.5 * lam * Trace(eps) ** 2 + mu * InnerProduct(eps, eps)


def green_lagrange(G):
    """Green–Lagrange strain ``½ (FᵀF - I)`` with ``F = I + G`` (2D or 3D)."""
    from ngsolve import Id

    d = dimension(G)
    F = Id(d) + G
    return 0.5 * (F.trans * F - Id(d))


def svk_energy(G, E, nu, plane="strain"):
    """St Venant–Kirchhoff ``λ/2 tr(E)² + μ E:E`` on the Green–Lagrange strain (3D; in 2D the
    in-plane strain, F33 = 1)."""
    from ngsolve import InnerProduct, Trace

    dimension(G, plane)
    mu, lam = lame(E, nu, plane)
    Eg = green_lagrange(G)
    return 0.5 * lam * Trace(Eg) ** 2 + mu * InnerProduct(Eg, Eg)


def jacobian(G):
    """``J = det F``, ``F = I + G`` (3D; in 2D of the in-plane deformation, F33 = 1 in plane
    strain)."""
    from ngsolve import Det, Id

    return Det(Id(dimension(G)) + G)


_PS_ITERATIONS = 8  # local Newton iterations for F33 (converged to round-off, see below)


def plane_stress_stretch(G, nu):
    """Out-of-plane stretch ``c = F33`` of a plane-stress Neo-Hookean solid.

    With ``F = diag(F2, c)``, ``J = J2 c`` (``J2 = det F2``) and the energy of thesis eq. 4.4,
    ``S33 = 0`` reads ``∂φ/∂c = (μ c² - μ + λ ln(J2 c)) / c = 0``.  In ``s = ln c`` this is

        h(s) = e^{2s} + a s - k = 0,   a = λ/μ = 2ν/(1-2ν),   k = 1 - a ln J2,

    convex and increasing in ``s``.  Newton's method started from an upper bound of the root
    (``s0 = ½ ln k`` if ``k > 1``, else ``s0 = 0``) decreases monotonically to it; eight
    iterations reach round-off for ``J2`` in ``[1e-8, 1e8]`` and every ``ν < 0.5`` (checked
    in numpy; seven suffice for ν ≤ 0.499).  Those iterations are frozen (``Freeze``: no
    derivatives through them) and one more Newton step ``s = s* - h(s*)/h'(s*)`` is taken
    with the live ``J2``: its value is ``s*`` and its first derivative is the implicit one,
    ``ds/dJ2 = -h_J2 / h_s``.  Because ``∂φ/∂c = 0`` at ``s*``, the energy's gradient and
    Hessian need nothing more (``d²ψ = φ_FF + φ_Fc c' + φ_cc c'²``), so residual and tangent
    are exact.  Only ``ν`` enters (``E`` cancels).

    2D only (plane stress).

    Parameters
    ----------
    G : CoefficientFunction
        In-plane displacement gradient (2x2); ``det(I + G) > 0`` is required.
    nu : float
        Poisson's ratio.

    Returns
    -------
    CoefficientFunction
        ``c = F33 > 0``.
    """
    from math import isclose

    from ngsolve import IfPos, exp, log

    a = 2.0 * nu / (1.0 - 2.0 * nu)
    if isclose(a, 0.0, abs_tol=1e-15):
        return 1.0 + 0.0 * jacobian(G)  # ν = 0: no lateral contraction
    lnJ2 = log(jacobian(G))
    k = 1.0 - a * lnJ2
    kf = k.Freeze()
    s = IfPos(kf - 1.0, 0.5 * log(IfPos(kf - 1.0, kf, 1.0)), 0.0 * kf)
    for _ in range(_PS_ITERATIONS):
        e2 = exp(2.0 * s)
        s = s - (e2 + a * s - kf) / (2.0 * e2 + a)
    s = s.Compile().Freeze()  # compiled: the unrolled iteration is a DAG, evaluated once
    e2 = exp(2.0 * s)
    s = s - (e2 + a * s - k) / (2.0 * e2 + a)
    return exp(s)


def neohookean_energy(G, E, nu, plane="strain"):
    """Compressible Neo-Hookean ``μ/2 (I1 - 3) - μ ln J + λ/2 (ln J)²`` (thesis eq. 4.4).

    3D: ``I1 = F:F``, ``J = det F``.  2D plane strain embeds ``F`` with ``F33 = 1``:
    ``I1 = F:F + 1``, ``J = det F``.  2D plane stress uses ``F33 = c`` from ``S33 = 0``
    (:func:`plane_stress_stretch`): ``I1 = F:F + c²``, ``J = c det F``, with the 3-D Lamé
    constants (the reduced ``λ*`` of :func:`lame` is the small-strain limit of this model, not
    an input to it).
    """
    from ngsolve import Id, InnerProduct, log

    d = dimension(G, plane)
    mu, lam = lame(E, nu, "strain")
    F = Id(d) + G
    if d == 3:
        I1 = InnerProduct(F, F)
        lnJ = log(jacobian(G))
    elif plane == "strain":
        I1 = InnerProduct(F, F) + 1.0  # tr(FᵀF) with F33 = 1
        lnJ = log(jacobian(G))
    else:
        c = plane_stress_stretch(G, nu)
        I1 = InnerProduct(F, F) + c * c
        lnJ = log(jacobian(G)) + log(c)
    return 0.5 * mu * (I1 - 3.0) - mu * lnJ + 0.5 * lam * lnJ ** 2


# ----------------------------------------------------------------------------------------
# Stresses for output, by automatic differentiation of an energy
# ----------------------------------------------------------------------------------------
def first_piola_kirchhoff(phi, G):
    """First Piola–Kirchhoff stress ``P = ∂φ/∂F = ∂φ/∂(∇u)`` (d x d: 3D, or in-plane in 2D).

    Parameters
    ----------
    phi : callable ``G -> CF``
        Strain-energy density per unit reference volume as a function of ``∇u``, e.g.
        ``lambda G: neohookean_energy(G, E, nu)``.
    G : CoefficientFunction
        The displacement gradient at which ``P`` is wanted (e.g. ``Grad(gfu)``).
    """
    Gv = G.MakeVariable()
    # compiled: symbolic Diff expands the energy's expression DAG into a tree, which uncompiled
    # evaluation walks node by node (measured, Ogden, 100 quads of order 2: S_xx set element-
    # wise in 110 s uncompiled, 0.8 s compiled); the values are the same
    return phi(Gv).Diff(Gv).Compile()


def second_piola_kirchhoff(phi, G):
    """Second Piola–Kirchhoff stress ``S = F⁻¹ P = ∂φ/∂E_GL`` (thesis eq. 4.3), d x d (3D, or
    in-plane in 2D).

    ``P`` comes from :func:`first_piola_kirchhoff`; ``F⁻¹ P`` is the kinematic identity
    ``P = F S``.  For the small-strain ``linear`` energy use ``P`` itself (``σ = ∂φ/∂ε``).
    """
    from ngsolve import Id, Inv

    return Inv(Id(dimension(G)) + G) * first_piola_kirchhoff(phi, G)


@dataclass(frozen=True)
class Material:
    """A named strain-energy model ``energy(G, E, ν, plane)`` (2D or 3D ``G``) and what it
    declares:

    * ``needs_positive_J``: a state with ``det F <= 0`` is outside the model's domain (the
      Newton guard checks it);
    * ``linear``: ``φ = ½ G:C:G`` with ``C`` independent of ``G`` (the residual is linear in u);
    * ``stress_free``: ``∂φ/∂G = 0`` at ``G = 0``;
    * ``proportional_to_E``: ``φ = E φ1(G; ν, plane)`` (the Lamé constants are proportional to
      ``E``; the plane-stress stretch of the Neo-Hookean model does not depend on it).

    :func:`~pacto_ng.physics.energy.make_energy` turns these into the energy's
    :class:`~pacto_ng.physics.traits.EnergyTraits`."""

    name: str
    energy: object
    needs_positive_J: bool
    linear: bool
    stress_free: bool
    proportional_to_E: bool


MATERIALS = {
    "linear": Material("linear", linear_energy, needs_positive_J=False, linear=True,
                       stress_free=True, proportional_to_E=True),
    "gnl": Material("gnl", svk_energy, needs_positive_J=False, linear=False, stress_free=True,
                    proportional_to_E=True),
    "neohookean": Material("neohookean", neohookean_energy, needs_positive_J=True, linear=False,
                           stress_free=True, proportional_to_E=True),
}


def _rubber_laws():
    """Mooney–Rivlin, Yeoh and Ogden (physics/hyperelastic.py), each with its default shape
    (the isochoric Neo-Hookean; a preset, physics/presets.py, gives a published one)."""
    return {name: Material(name, Law(name, DEFAULT_SHAPES[name]), needs_positive_J=True,
                           linear=False, stress_free=True, proportional_to_E=True)
            for name in LAWS}


MATERIALS.update(_rubber_laws())

#: the mechanics models: every material, and the Wang interpolation of a hyperelastic one
#: with the linear one (physics/wang.py)
MODELS = tuple(MATERIALS) + ("wang",)


def get_material(name: str) -> Material:
    try:
        return MATERIALS[name]
    except KeyError:
        raise ValueError(f"unknown material model '{name}' (choose from {', '.join(MATERIALS)})") from None
