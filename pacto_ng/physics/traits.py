"""What a strain-energy density declares about itself (:class:`EnergyTraits`, carried as its
``traits`` attribute), from which the mechanics block picks its assembly, and the error a
declaration that contradicts the computation raises (:class:`DeclarationError`)."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from .quadrature import GUARD_POINTS


class DeclarationError(ValueError):
    """An energy's (or a body load's) declaration contradicts what it computes: raised by the
    check of the declaration when the mechanics block is built, never silently passed over."""


@dataclass(frozen=True)
class EnergyTraits:
    """What a strain-energy density ``φ(G; fields)`` declares about itself.

    :class:`~pacto_ng.physics.mechanics.Mechanics` chooses its assembly from this declaration
    (nothing is probed); the defaults declare nothing and give the general route (``Variation``:
    automatic differentiation of the energy, always correct).  An energy carries its traits as
    the attribute ``traits`` (:func:`declare`, :func:`traits_of`).

    reads : tuple of str or None
        The fields ``φ`` depends on (None: any of the block's fields).  A field it does not read
        gives no strain-energy sensitivity, and may enter the residual through a body load
        linear in it (the Darcy pressure: the load vector ``B p`` with a fixed matrix ``B``).
    quadratic : bool
        ``φ = ½ G:C:G`` exactly, with ``C = ∂²φ/∂G²`` independent of ``G`` and constant on each
        element (a function of element-wise fields only, not of the position).  A linear,
        conservative block then assembles ``K`` from ``C`` per element and takes the strain
        energy, its gradient and the field sensitivities from ``C``.  Implies ``stress_free``.
        Verified when the block is built (a wrong declaration raises ``ValueError``).
    stress_free : bool
        ``∂φ/∂G = 0`` at ``G = 0`` for every value of the fields: the residual at ``u = 0`` is
        minus the load vector (its norm, Newton's reference, without evaluating the energy).
    modulus : callable or None
        ``values -> (E, {field: ∂E/∂field})`` on numpy arrays of the element values of the fields
        read: ``φ(G; fields) = E(fields) φ1(G)`` on every element with one fixed ``φ1`` (SIMP).
        With ``quadratic``, ``C = E C1``: from the second design on (the first in an
        optimisation) ``K`` and the field sensitivities come from element matrices computed
        once (:class:`~pacto_ng.physics.scatter.ElementMatrices`) and ``E`` per design from
        numpy.
        Verified against the energy's CF when the block is built (``ValueError`` if wrong).
    guard_points : {"element", "quadrature"}
        Where Newton's guard (``det F > 0``, or the model's own guard CF) must hold for the
        energy to be defined: ``"quadrature"``, the points of the forms' quadrature rule, the
        only points where the discrete energy, residual and tangent are evaluated (its
        logarithm, say, is then defined wherever it is used); ``"element"`` (what an energy
        that declares nothing gets), also the vertices, edge midpoints and centroid of every
        element (:func:`~pacto_ng.physics.quadrature.guard_rules`).
    """

    reads: tuple[str, ...] | None = None
    quadratic: bool = False
    stress_free: bool = False
    modulus: Callable | None = None
    guard_points: str = "element"

    def __post_init__(self):
        if self.guard_points not in GUARD_POINTS:
            raise ValueError(f"guard_points must be one of {', '.join(GUARD_POINTS)} (got "
                             f"'{self.guard_points}')")
        if self.reads is not None:
            object.__setattr__(self, "reads", tuple(self.reads))
        if self.quadratic and not self.stress_free:
            object.__setattr__(self, "stress_free", True)  # ∂(½ G:C:G)/∂G = C G = 0 at G = 0


#: the traits of an energy that declares nothing: the general route
GENERAL = EnergyTraits()


def traits_of(energy) -> EnergyTraits:
    """The :class:`EnergyTraits` an energy declares (its ``traits`` attribute), else
    :data:`GENERAL`."""
    traits = getattr(energy, "traits", None)
    if traits is None:
        return GENERAL
    if not isinstance(traits, EnergyTraits):
        raise TypeError(f"energy.traits must be an EnergyTraits (got {type(traits).__name__})")
    return traits


def declare(energy: Callable, **traits) -> Callable:
    """Attach ``EnergyTraits(**traits)`` to the callable ``energy`` and return it."""
    energy.traits = EnergyTraits(**traits)
    return energy
