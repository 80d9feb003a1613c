"""Strain-energy densities φ(∇u; E, ν) as NGSolve CoefficientFunctions (SPEC §3).

Every model is a pure function of the 2x2 displacement gradient ``G = ∇u`` (a CF), the
Young's modulus ``E`` (a CF, e.g. SIMP of the density) and Poisson's ratio ``ν``.  Plane strain
embeds ``F`` in 3x3 with ``F33 = 1``.  Plane stress uses the reduced Lamé constant
``λ* = 2λμ/(λ+2μ)`` for the quadratic models (exact for linear elasticity; the usual
plane-stress St Venant–Kirchhoff).  The residual and tangent come from ``Variation`` — nothing
is differentiated by hand.

| name | φ |
|---|---|
| ``linear`` | ``λ/2 tr(ε)² + μ ε:ε`` (thesis eqs 2.11–2.12) |
| ``gnl`` | St Venant–Kirchhoff ``λ/2 tr(E)² + μ E:E`` on Green–Lagrange ``E`` |
| ``neohookean`` | ``μ/2 (I1 - 3) - μ ln J + λ/2 (ln J)²`` (thesis eq. 4.4) |
"""
from __future__ import annotations

from dataclasses import dataclass

MODELS = ("linear", "gnl", "neohookean", "wang")


def lame(E, nu, plane: str = "strain"):
    """Lamé constants (μ, λ); plane stress returns the reduced λ*."""
    mu = E / (2.0 * (1.0 + nu))
    lam = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))
    if plane == "stress":
        lam = 2.0 * lam * mu / (lam + 2.0 * mu)
    return mu, lam


def linear_energy(G, E, nu, plane="strain"):
    """Small-strain energy ``λ/2 tr(ε)² + μ ε:ε`` with ``ε = sym G``."""
    from ngsolve import InnerProduct, Trace

    mu, lam = lame(E, nu, plane)
    eps = 0.5 * (G + G.trans)
    return 0.5 * lam * Trace(eps) ** 2 + mu * InnerProduct(eps, eps)


def green_lagrange(G):
    from ngsolve import Id

    F = Id(2) + G
    return 0.5 * (F.trans * F - Id(2))


def svk_energy(G, E, nu, plane="strain"):
    """St Venant–Kirchhoff ``λ/2 tr(E)² + μ E:E`` on the Green–Lagrange strain (F33 = 1)."""
    from ngsolve import InnerProduct, Trace

    mu, lam = lame(E, nu, plane)
    Eg = green_lagrange(G)
    return 0.5 * lam * Trace(Eg) ** 2 + mu * InnerProduct(Eg, Eg)


def jacobian(G):
    """``J = det F`` of the in-plane deformation (F33 = 1 in plane strain)."""
    from ngsolve import Det, Id

    return Det(Id(2) + G)


def neohookean_energy(G, E, nu, plane="strain"):
    """Compressible Neo-Hookean ``μ/2 (I1 - 3) - μ ln J + λ/2 (ln J)²`` (plane strain, F33 = 1)."""
    from ngsolve import Id, InnerProduct, log

    if plane != "strain":
        raise ValueError("the neohookean model is implemented for plane strain only")
    mu, lam = lame(E, nu, plane)
    F = Id(2) + G
    I1 = InnerProduct(F, F) + 1.0  # tr(FᵀF) with F33 = 1
    lnJ = log(jacobian(G))
    return 0.5 * mu * (I1 - 3.0) - mu * lnJ + 0.5 * lam * lnJ ** 2


@dataclass(frozen=True)
class Material:
    """A named strain-energy model.  ``energy(G, E, ν, plane)``; ``needs_positive_J`` says whether
    a state with ``det F <= 0`` is outside the model's domain (the Newton guard checks it)."""

    name: str
    energy: object
    needs_positive_J: bool
    linear: bool


MATERIALS = {
    "linear": Material("linear", linear_energy, False, True),
    "gnl": Material("gnl", svk_energy, False, False),
    "neohookean": Material("neohookean", neohookean_energy, True, False),
}


def get_material(name: str) -> Material:
    try:
        return MATERIALS[name]
    except KeyError:
        raise ValueError(f"unknown material model '{name}' (choose from {', '.join(MATERIALS)})") from None
