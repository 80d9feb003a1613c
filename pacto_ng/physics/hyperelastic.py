"""Mooney–Rivlin, Yeoh and Ogden strain energies (docs/theory.md §3, "Rubber models").

Each energy is a pure function of the displacement gradient ``G = ∇u`` (2x2 or 3x3 CF; the
dimension comes from ``G``, 2D is plane strain with ``F33 = 1``), Young's modulus ``E`` (a CF,
e.g. SIMP) and Poisson's ratio ``ν``, with residual and tangent left to NGSolve's automatic
differentiation.  They use the isochoric/volumetric split of Abaqus (the convention published
rubber and silicone fits assume, Abaqus Theory Manual §4.6.1 "Hyperelastic behavior of rubberlike
materials"):

    φ = W_iso(Ī1, Ī2 or λ̄_i) + K/2 (J - 1)²,   Ī1 = J^(-2/3) I1,  Ī2 = J^(-4/3) I2,
    λ̄_i = J^(-1/3) λ_i,

    Mooney–Rivlin   W_iso = C10 (Ī1 - 3) + C01 (Ī2 - 3),                 μ0 = 2 (C10 + C01)
    Yeoh            W_iso = C10 (Ī1 - 3) + C20 (Ī1 - 3)² + C30 (Ī1 - 3)³, μ0 = 2 C10
    Ogden           W_iso = Σ_p 2 μ_p/α_p² (λ̄1^α_p + λ̄2^α_p + λ̄3^α_p - 3), μ0 = Σ_p μ_p

with the volumetric term ``U = (1/D1)(J - 1)²`` of Abaqus, ``D1 = 2/K``, and the bulk modulus
from ``ν``: ``K = E / (3 (1 - 2ν))`` (the higher ``D_i`` of Yeoh and Ogden are zero).  The
coefficients are given *relative to the small-strain shear modulus* ``μ0 = E / (2 (1 + ν))``,
so that ``φ = E φ1(G; shape, ν)``: SIMP scales the whole energy, and at small strain ``φ``
is the linear energy with ``(E, ν)`` (``μ0 |dev ε|² + K/2 tr(ε)²``).  A published fit
``(C10, C01, ...)`` in Pa gives its shape by dividing by its own ``μ0`` and its modulus as
``E = 2 μ0 (1 + ν)`` (:mod:`~pacto_ng.physics.presets`).

Plane stress is refused (``ValueError`` naming ``plane``): the split energies would need the
out-of-plane stretch from ``S33 = 0`` of each law, which is not implemented.

Ogden's principal stretches
---------------------------
``Σ_i λ̄_i^α = Σ_i c_i^a`` with ``c_i`` the eigenvalues of ``C̄ = J^(-2/3) C`` and
``a = α/2``: a smooth symmetric function of ``C̄``, but the eigenvalues are not differentiable
where two coincide (uniaxial and equibiaxial states) and a closed-form eigen-solver gives NaN
derivatives there and at ``F = I``.  It is evaluated from the invariants ``Ī1, Ī2`` (``det C̄ =
1``) in two branches, switched with ``IfPos``:

* near the triple coincidence (``J2 = Ī1²/3 - Ī2 < τ3 m²``, ``m = Ī1/3``, ``τ3 = 1e-6``): the
  Taylor series about ``m`` in the deviator ``D = C̄ - m I``, ``Σ_k f^(k)(m)/k! tr(D^k)`` with
  ``tr D^k`` as monomials in ``J2`` and ``J3 = det D`` (Cayley–Hamilton), to ``k = 6``: a
  polynomial in the invariants, exact in value and derivatives to round-off at ``F = I``
  (every eigenvalue is within 0.12 % of ``m`` there; the first term left out is below 3e-18
  of ``f(m)`` for ``|α| <= 10``);
* elsewhere the eigenvalue farthest from ``m`` (a simple root of ``p(c) = c³ - Ī1 c² + Ī2 c -
  1``, separated from the two others by at least ``sqrt(2 J2 / 3)``) from the trigonometric
  formula, frozen (no derivatives), then one Chebyshev step ``c + δ - p''/(2p') δ²``,
  ``δ = -p/p'``, with the live invariants: its value is the root and its first *and second*
  derivatives are those of the root (implicit function theorem; a Newton step alone gives the
  first only).  The two other eigenvalues are ``b ± δ`` with ``b = (Ī1 - c1)/2`` and
  ``δ²/b² = t = 1 - 1/(c1 b²)``, and ``f(b + δ) + f(b - δ) = b^a ((1 + √t)^a + (1 - √t)^a)``
  (even in δ) is evaluated as it is for ``t > τ2`` (``τ2 = 1e-6``) and as its Taylor series
  ``b^a (2 + 2 Σ_k binom(a, 2k) t^k)`` (to ``k = 3``) below: smooth at the equal pair of a
  uniaxial or equibiaxial state.

The expressions are written to keep the expression *tree* short (symbolic ``Diff`` and
uncompiled evaluation walk the tree, not the DAG).  The branch not taken is evaluated on a
fixed, well-separated state (eigenvalues 1/2, 1, 2), so that it never produces a NaN that the
tangent could pick up.
"""
from __future__ import annotations

from dataclasses import dataclass
from math import fsum
from typing import Callable

from .gradient import dimension

#: the rubber laws of this module (``--model``)
LAWS = ("mooney_rivlin", "yeoh", "ogden")

TAU_TRIPLE = 1e-6  # J2 / m² below which the triple-coincidence Taylor series is used
TAU_PAIR = 1e-6    # δ² / b² below which the equal-pair Taylor series is used
TRIPLE_ORDER = 6   # highest power of the deviator in the triple series
PAIR_ORDER = 3     # highest power of δ²/b² in the pair series
_SAFE = (3.5, 3.5)  # Ī1, Ī2 of eigenvalues (1/2, 1, 2): the state of the branch not taken


def bulk_modulus(E, nu):
    """``K = E / (3 (1 - 2ν))``: the small-strain bulk modulus of ``(E, ν)``."""
    return E / (3.0 * (1.0 - 2.0 * nu))


def shear_modulus(E, nu):
    """``μ0 = E / (2 (1 + ν))``."""
    return E / (2.0 * (1.0 + nu))


# ----------------------------------------------------------------------------------------
# kinematics
# ----------------------------------------------------------------------------------------
def invariants(G, plane: str = "strain"):
    """``(Ī1, Ī2, J)`` of ``F = I + G`` (3D; 2D plane strain with ``F33 = 1``).

    ``ValueError`` for plane stress (not implemented for the split energies) and for an
    unknown ``plane`` or a gradient that is not 2x2 or 3x3."""
    from ngsolve import Det, Id, InnerProduct, Trace

    d = dimension(G, plane)
    if plane == "stress":
        raise ValueError("plane=stress is not implemented for the Mooney–Rivlin, Yeoh and Ogden "
                         "models (use plane=strain, or a 3D mesh)")
    F = Id(d) + G
    C = F.trans * F
    extra = 1.0 if d == 2 else 0.0  # C33 = 1 in plane strain
    I1 = Trace(C) + extra
    trC2 = InnerProduct(C, C) + extra
    I2 = 0.5 * (I1 * I1 - trC2)
    J = Det(F)
    Jm23 = J ** (-2.0 / 3.0)
    return Jm23 * I1, Jm23 * Jm23 * I2, J


def _volumetric(J, E, nu):
    return 0.5 * bulk_modulus(E, nu) * (J - 1.0) ** 2


# ----------------------------------------------------------------------------------------
# the laws: shapes (coefficients / μ0) and energies
# ----------------------------------------------------------------------------------------
def _check_sum(name, total, want):
    if abs(total - want) > 1e-12 * max(1.0, abs(want)):
        raise ValueError(f"{name}: the coefficients relative to μ0 must sum to {want:g} "
                         f"(got {total:.15g})")


def mooney_rivlin_energy(G, E, nu, plane="strain", shape=(0.5, 0.0)):
    """Mooney–Rivlin ``C10 (Ī1 - 3) + C01 (Ī2 - 3) + K/2 (J - 1)²`` (Abaqus split).

    ``shape = (C10/μ0, C01/μ0)``, summing to 1/2 (``μ0 = 2 (C10 + C01)``); ``(0.5, 0)`` is
    the isochoric Neo-Hookean ``μ0/2 (Ī1 - 3) + K/2 (J - 1)²``."""
    a10, a01 = (float(v) for v in shape)
    _check_sum("mooney_rivlin", a10 + a01, 0.5)
    I1b, I2b, J = invariants(G, plane)
    mu = shear_modulus(E, nu)
    return mu * (a10 * (I1b - 3.0) + a01 * (I2b - 3.0)) + _volumetric(J, E, nu)


def yeoh_energy(G, E, nu, plane="strain", shape=(0.5, 0.0, 0.0)):
    """Yeoh ``Σ_i Ci0 (Ī1 - 3)^i + K/2 (J - 1)²`` (i = 1..3, Abaqus split).

    ``shape = (C10/μ0, C20/μ0, C30/μ0)`` with ``C10/μ0 = 1/2``."""
    coeffs = tuple(float(v) for v in shape)
    if not 1 <= len(coeffs) <= 3:
        raise ValueError(f"yeoh: one to three coefficients (got {len(coeffs)})")
    _check_sum("yeoh (C10 alone)", coeffs[0], 0.5)
    I1b, I2b, J = invariants(G, plane)
    mu = shear_modulus(E, nu)
    x = I1b - 3.0
    w = coeffs[0] * x
    for i, c in enumerate(coeffs[1:], start=2):
        if c != 0.0:
            w = w + c * x ** i
    return mu * w + _volumetric(J, E, nu)


def ogden_energy(G, E, nu, plane="strain", shape=((1.0, 2.0),)):
    """Ogden ``Σ_p 2 μ_p/α_p² (Σ_i λ̄_i^α_p - 3) + K/2 (J - 1)²`` (Abaqus form and split).

    ``shape = ((μ_1/μ0, α_1), (μ_2/μ0, α_2), ...)`` with ``Σ μ_p/μ0 = 1`` and ``α_p ≠ 0``; one
    term ``(1, 2)`` is the isochoric Neo-Hookean.  The stretch sums are
    :func:`stretch_power_sums` (regularised at equal stretches, module docstring)."""
    terms = tuple((float(m), float(a)) for m, a in shape)
    if not terms:
        raise ValueError("ogden: at least one term")
    if any(a == 0.0 for _, a in terms):
        raise ValueError("ogden: every exponent α_p must be non-zero")
    _check_sum("ogden", fsum(m for m, _ in terms), 1.0)
    I1b, I2b, J = invariants(G, plane)
    mu = shear_modulus(E, nu)
    sums = stretch_power_sums(I1b, I2b, [0.5 * a for _, a in terms])
    w = 0.0
    for (m, a), s in zip(terms, sums):
        w = w + (2.0 * m / (a * a)) * (s - 3.0)
    return mu * w + _volumetric(J, E, nu)


# ----------------------------------------------------------------------------------------
# Σ_i c_i^a over the eigenvalues of an isochoric C̄ (det C̄ = 1), smooth at coincidences
# ----------------------------------------------------------------------------------------
def _binom(a: float, k: int) -> float:
    """The generalised binomial coefficient ``a (a-1) ... (a-k+1) / k!``."""
    out = 1.0
    for j in range(k):
        out *= (a - j) / (j + 1)
    return out


def _clamp(x, lo, hi):
    from ngsolve import IfPos

    return IfPos(x - hi, hi, IfPos(lo - x, lo, x))


def _traceless_power_sums(J2, J3):
    """``tr D^k`` for k = 0..:data:`TRIPLE_ORDER` of a traceless 3x3 ``D`` with ``J2 = tr D²/2``
    and ``J3 = det D``, as monomials in J2, J3 (Cayley–Hamilton ``D³ = J2 D + J3 I``):
    ``p_{k+3} = J2 p_{k+1} + J3 p_k`` expanded (a short expression tree, not a recurrence)."""
    table = {0: {(0, 0): 3.0}, 1: {}, 2: {(1, 0): 2.0}}
    for k in range(3, TRIPLE_ORDER + 1):
        row = {}
        for (i, j), c in table[k - 2].items():
            row[(i + 1, j)] = row.get((i + 1, j), 0.0) + c
        for (i, j), c in table[k - 3].items():
            row[(i, j + 1)] = row.get((i, j + 1), 0.0) + c
        table[k] = row
    return table


def stretch_power_sums(I1b, I2b, exponents):
    """``[Σ_i c_i^a for a in exponents]`` for the eigenvalues ``c_i`` of an isochoric right
    Cauchy–Green tensor with invariants ``Ī1, Ī2`` (``det = 1``), as CFs that are smooth (value,
    first and second derivatives) everywhere, including ``C̄ = I`` and equal pairs (module
    docstring).  Written to keep the expression *tree* short: symbolic ``Diff`` and uncompiled
    evaluation walk it as a tree."""
    from ngsolve import CF, IfPos, acos, cos, sqrt

    exponents = [float(a) for a in exponents]
    m = I1b / 3.0
    J2 = I1b * I1b / 3.0 - I2b
    J3 = (2.0 / 27.0) * I1b ** 3 - I1b * I2b / 3.0 + 1.0
    spread = J2 - TAU_TRIPLE * m * m  # > 0: the spectral branch

    # -- the triple-coincidence branch: Taylor series about m in the deviator ------------------
    table = _traceless_power_sums(J2, J3)
    monomials = {}
    for k in range(2, TRIPLE_ORDER + 1):
        for ij in table[k]:
            if ij not in monomials:
                i, j = ij
                monomials[ij] = (J2 ** i if i else 1.0) * (J3 ** j if j else 1.0)
    triple = []
    for a in exponents:
        s = 3.0
        for k in range(2, TRIPLE_ORDER + 1):
            c = _binom(a, k)
            if c != 0.0:
                poly = sum(coef * monomials[ij] for ij, coef in table[k].items())
                s = s + c * poly / m ** k
        triple.append(m ** a * s)

    # -- the spectral branch, on a safe state where it is not taken -----------------------------
    i1 = IfPos(spread, I1b, _SAFE[0])
    i2 = IfPos(spread, I2b, _SAFE[1])
    # the eigenvalue farthest from the mean, frozen (no derivatives): trigonometric formula
    frozen = CF((i1, i2)).Compile().Freeze()  # one compiled evaluation of both per point
    i1f, i2f = frozen[0], frozen[1]
    j2f = i1f * i1f / 3.0 - i2f
    j3f = (2.0 / 27.0) * i1f ** 3 - i1f * i2f / 3.0 + 1.0
    sf = sqrt(j2f / 3.0)
    # |r| < 1 strictly: Freeze does not stop NGSolve's automatic differentiation from forming
    # acos'(r) = -1/sqrt(1 - r²) (infinite at |r| = 1, uniaxial states) before zeroing it; the
    # clamp moves c0 by ~1e-15 relative, which the Chebyshev step below removes
    r = _clamp(j3f / (2.0 * sf ** 3), -1.0 + 1e-14, 1.0 - 1e-14)
    c0 = i1f / 3.0 + IfPos(r, 1.0, -1.0) * 2.0 * sf * cos(acos(IfPos(r, r, -r)) / 3.0)
    c0 = c0.Compile().Freeze()
    # one Chebyshev step with the live invariants: c0 + δ - p''/(2 p') δ², δ = -p/p'; its value
    # is the root and its first and second derivatives are the root's (implicit function
    # theorem: the δ² term supplies -p'' c'² / p' of the second derivative)
    dp = (3.0 * c0 - 2.0 * i1) * c0 + i2
    delta = -(((c0 - i1) * c0 + i2) * c0 - 1.0) / dp
    c1 = c0 + delta - (3.0 * c0 - i1) / dp * delta * delta
    b = 0.5 * (i1 - c1)
    t = 1.0 - 1.0 / (c1 * b * b)  # δ²/b² of the other two eigenvalues b ± δ (product 1/c1)
    pair_open = t - TAU_PAIR
    root = sqrt(IfPos(pair_open, t, TAU_PAIR))
    spectral = []
    for a in exponents:
        open_pair = (1.0 + root) ** a + (1.0 - root) ** a
        taylor = 0.0
        for k in range(PAIR_ORDER, 0, -1):  # Horner in t: 2 Σ_k binom(a, 2k) t^k
            taylor = (taylor + 2.0 * _binom(a, 2 * k)) * t
        spectral.append(c1 ** a + b ** a * IfPos(pair_open, open_pair, 2.0 + taylor))
    return [IfPos(spread, s, t3) for s, t3 in zip(spectral, triple)]


# ----------------------------------------------------------------------------------------
# a law with its shape: the energy (G, E, ν, plane) of a Material
# ----------------------------------------------------------------------------------------
ENERGIES = {"mooney_rivlin": mooney_rivlin_energy, "yeoh": yeoh_energy, "ogden": ogden_energy}


@dataclass(frozen=True)
class Law:
    """A rubber law with its dimensionless shape: callable ``(G, E, ν, plane) -> CF``, the
    energy of :class:`~pacto_ng.physics.materials.Material` (``φ = E φ1``)."""

    name: str
    shape: tuple

    def __post_init__(self):
        if self.name not in ENERGIES:
            raise ValueError(f"unknown rubber law '{self.name}' (choose from {', '.join(LAWS)})")

    def __call__(self, G, E, nu, plane="strain"):
        return ENERGIES[self.name](G, E, nu, plane, shape=self.shape)

    @property
    def energy(self) -> Callable:
        return self
