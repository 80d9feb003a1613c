"""Material and flow interpolations as pure factories: numpy versions and NGSolve CF versions.

* smoothed Heaviside ``H(ρ; η, β) = (tanh(βη) + tanh(β(ρ-η))) / (tanh(βη) + tanh(β(1-η)))``
  (docs/theory.md §1 projection, §2 flow/drainage, §3 Wang γ);
* SIMP ``E(ρ) = E0 + ρ^p (E1 - E0)`` (thesis eq. A.23) and the two-material law (thesis eq. 6.1).

The Darcy flow coefficient and drainage built on the Heaviside are in
:mod:`pacto_ng.physics.darcy`.
"""
from __future__ import annotations

import numpy as np

_CLAMP = 20.0  # tanh(20) = 1 - 8e-18: beyond this tanh is 1 to double precision


def heaviside_np(rho, eta: float, beta: float):
    """Smoothed Heaviside on arrays (identity for beta -> 0)."""
    rho = np.asarray(rho, dtype=float)
    if beta < 1e-8:
        return rho.copy()
    den = np.tanh(beta * eta) + np.tanh(beta * (1.0 - eta))
    return (np.tanh(beta * eta) + np.tanh(beta * (rho - eta))) / den


def heaviside_deriv_np(rho, eta: float, beta: float):
    """dH/dρ on arrays."""
    rho = np.asarray(rho, dtype=float)
    if beta < 1e-8:
        return np.ones_like(rho)
    den = np.tanh(beta * eta) + np.tanh(beta * (1.0 - eta))
    return beta * (1.0 - np.tanh(beta * (rho - eta)) ** 2) / den


def power_np(rho, penal: float):
    """``(ρ^p, d ρ^p/dρ)`` on arrays, 0 below 1e-30 as :func:`power_cf`."""
    rho = np.asarray(rho, dtype=float)
    on = rho > 1e-30
    r = np.where(on, rho, 1.0)
    return np.where(on, r ** penal, 0.0), np.where(on, penal * r ** (penal - 1.0), 0.0)


def simp_np(rho, E0: float, E1: float, penal: float):
    """``(E, dE/dρ)`` of :func:`simp_cf` on arrays."""
    a, da = power_np(rho, penal)
    return E0 + a * (E1 - E0), da * (E1 - E0)


def simp2_np(rho1, rho2, E0: float, E1: float, E2: float, penal: float):
    """``(E, dE/dρ1, dE/dρ2)`` of :func:`simp2_cf` on arrays."""
    a, da = power_np(rho1, penal)
    b, db = power_np(rho2, penal)
    inner = (1.0 - b) * E1 + b * E2
    return (1.0 - a) * E0 + a * inner, da * (inner - E0), a * db * (E2 - E1)


def tanh_cf(z):
    """Overflow-safe tanh of a CoefficientFunction that differentiates correctly with ``Diff``."""
    from ngsolve import IfPos, exp

    zc = IfPos(z - _CLAMP, _CLAMP, IfPos(-_CLAMP - z, -_CLAMP, z))
    return 1.0 - 2.0 / (exp(2.0 * zc) + 1.0)


def heaviside_cf(rho, eta, beta):
    """Smoothed Heaviside of a CoefficientFunction; ``eta`` and ``beta`` may be Parameters."""
    import math

    if isinstance(beta, (int, float)) and isinstance(eta, (int, float)):
        if beta < 1e-8:
            return rho
        den = math.tanh(beta * eta) + math.tanh(beta * (1.0 - eta))
        return (math.tanh(beta * eta) + tanh_cf(beta * (rho - eta))) / den
    den = tanh_cf(beta * eta) + tanh_cf(beta * (1.0 - eta))
    return (tanh_cf(beta * eta) + tanh_cf(beta * (rho - eta))) / den


def power_cf(rho, penal):
    """``ρ^p`` that is 0 (with zero derivative) at ρ = 0.

    NGSolve differentiates ``ρ**p`` through ``log ρ``, which gives NaN at ρ = 0 even where the
    derivative is taken in a direction that does not involve ρ (the residual in u), and so do
    subnormal densities (1e-320 occurs in filtered designs).  Below 1e-30 the power is taken
    as 0: with p >= 1 it is below 1e-30 there, far under any void stiffness E0/E1.
    """
    from ngsolve import IfPos

    return IfPos(rho - 1e-30, rho ** penal, 0.0)


def simp_cf(rho, E0, E1, penal):
    """SIMP modulus ``E0 + ρ^p (E1 - E0)``."""
    return E0 + power_cf(rho, penal) * (E1 - E0)


def simp2_cf(rho1, rho2, E0, E1, E2, penal):
    """Two-material SIMP (thesis eq. 6.1): ``(1-ρ1^p) E0 + ρ1^p [(1-ρ2^p) E1 + ρ2^p E2]``."""
    a = power_cf(rho1, penal)
    b = power_cf(rho2, penal)
    return (1.0 - a) * E0 + a * ((1.0 - b) * E1 + b * E2)
