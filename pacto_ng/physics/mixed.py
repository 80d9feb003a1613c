"""The mixed displacement–pressure formulation of a hyperelastic energy: near-incompressible
solids without volumetric locking (docs/theory.md, "The mixed formulation").

A pure-displacement finite element locks as ν -> 1/2: the volume change ``J = det F`` must
then stay 1 at every quadrature point, which a polynomial displacement field can only do by not
moving.  The three-field formulation of Simo, Taylor and Pister (1985) relaxes the constraint
to a projection on each element.  Two discontinuous element fields join the displacement
``u``: the dilatation ``Θ = 1 + ϑ`` and the pressure ``p̃``, and the energy ``φ`` of any model
is evaluated at the modified deformation gradient

    F̄ = (Θ / J)^(1/d) F,     det F̄ = Θ,

with the constraint ``Θ = J`` imposed weakly on each element by ``p̃``:

    Π(u, ϑ, p̃) = t ∫ φ(F̄ - I) + p̃ (J - Θ) dΩ + (loads, springs).

``d`` is the mesh's dimension; in 2D plane strain ``F`` is the in-plane gradient (``F33 = 1``
stays), so that ``det F̄ = Θ`` there too.  ``ϑ`` is stored instead of ``Θ`` so that the zero
vector is the undeformed, stress-free state (warm starts from zero, the load at ``u = 0``).
The element fields are local dofs: the tangent is statically condensed to the displacement's
coupling dofs (:class:`~pacto_ng.physics.solvers.LinearSolver`), a system as large as the
displacement formulation's and symmetric positive definite at a stable equilibrium.

The pairs (:meth:`Mixed.displacement_options`, :class:`Mixed`), at displacement order ``k``:
on quadrilaterals and hexahedra the element fields are discontinuous of order ``k - 1`` (Q1/P0,
the mean dilatation, and Q2/P1); on triangles the displacement gets the element bubble of
order ``k + 1`` and the element fields are of order ``k - 1`` (P2+/P1, the Crouzeix–Raviart
pair; plain P2/P0 was measured 4.4 % too flexible on the locking benchmark's mesh, P2/P1
without the bubble as stiff as the displacement formulation); on tetrahedra they are of order
``k - 2`` (P2/P0: the bubble of a tetrahedron is of order 4, and P2/P1 without it measured as
stiff as the displacement formulation, tests/physics/test_mixed.py).  P1 on simplices has no stable pair of this kind
(P1/P0 locks: as many constraints as elements, about twice the nodes): refused.  Plane stress
has no incompressibility constraint (the thickness is free to change): refused, as is the
linear model (whose small-strain energy this formulation would make nonlinear).

The guard: ``J > 0`` and ``Θ > 0`` at the quadrature points (``(Θ/J)^(1/d)`` is real), and the
model's own guard at ``F̄``.  The Wang model brings its own mixed form
(:meth:`~pacto_ng.physics.wang.WangModel.mixed_energy`): the dilatation acts on its
large-strain part ``I + γ∇u`` only, so that void keeps its linear energy and accepts any
``det(I + ∇u)``, as in the displacement formulation.
"""
from __future__ import annotations

from dataclasses import dataclass

from ..errors import InputError
from ..settings import Settings, setting

FORMULATIONS = ("auto", "displacement", "mixed")

# ``auto`` takes the mixed formulation from this Poisson's ratio on (hyperelastic models, plane
# strain or 3D, quadrilaterals and hexahedra at any order, triangles at order >= 2).  Measured by
# ``python3 -m benchmarks locking`` (docs/studies.md, "Volumetric locking"), tip deflection of
# a Neo-Hookean cantilever in plane strain against a converged reference: Q1 displacement -2.4 %
# at ν = 0.4, -4.9 % at 0.45, -19 % at 0.49, -90 % at 0.4999; Q1/P0 mixed +0.2 % to 0.0 %
# throughout; P2 displacement -1.3 % at 0.45, -2.2 % at 0.4999 (and 9 Newton iterations against
# 4); P2+/P1 mixed -0.6 % and -0.9 %.  On tetrahedra ``auto`` keeps the displacement
# formulation: P2/P0 was not the closer one on a 2-element-thick beam (tests/physics/test_mixed.py
# measured +6.5 % against -7 % at ν = 0.4999, and +7 % against -0.7 % at ν = 0.3).
NU_MIXED = 0.45


def formulation_for(setting: str, *, model: str, nu: float, plane: str, dim: int, order: int,
                    simplices: bool) -> str:
    """``"displacement"`` or ``"mixed"`` for a run (``setting``: auto | displacement | mixed);
    :class:`~pacto_ng.params.InputError` naming ``formulation`` for a combination the mixed
    formulation does not apply to (see the module)."""
    if setting not in FORMULATIONS:
        raise InputError(f"formulation: must be one of {', '.join(FORMULATIONS)} (got "
                         f"'{setting}')")
    applies = model != "linear" and (dim == 3 or plane == "strain")
    if setting == "auto":
        stable = not simplices or (dim == 2 and order >= 2)
        return "mixed" if applies and stable and nu >= NU_MIXED else "displacement"
    if setting == "mixed":
        if model == "linear":
            raise InputError("formulation: mixed applies to the hyperelastic models (the linear "
                             "model's small-strain energy has no finite-strain dilatation); "
                             "use --model neohookean, gnl or wang")
        if dim == 2 and plane == "stress":
            raise InputError("formulation: mixed applies to plane strain and 3D (plane stress "
                             "has no incompressibility constraint: the thickness is free)")
        if simplices and order < 2:
            raise InputError("formulation: mixed needs --set order=2 on triangles and "
                             "tetrahedra (P1 with an element pressure still locks)")
    return setting


def stored_energy(energy, mixed, parts, coeffs):
    """The stored energy density of a state's components ``parts``: ``φ(∇u)`` of ``(u,)``
    (``mixed`` None), or :meth:`Mixed.energy`'s ``φ(F̄ - I) + p̃ (J - Θ)`` of ``(u, ϑ, p̃)``."""
    from ngsolve import Grad

    if mixed is None:
        return energy(Grad(parts[0]), coeffs)
    u, theta, p = parts
    return mixed.energy(energy, Grad(u), theta, p, coeffs)


@dataclass(frozen=True)
class FormulationSettings(Settings):
    """The finite element formulation of the mechanics."""

    formulation: str = setting(
        "auto", "", "displacement | mixed (u with an element dilatation and pressure, "
        f"statically condensed: no locking as nu -> 0.5) | auto (mixed from nu >= {NU_MIXED} "
        "for the hyperelastic models in plane strain or 3D, on quadrilaterals, hexahedra and "
        "triangles at order >= 2)",
        choices=FORMULATIONS)


def has_simplices(mesh) -> bool:
    """Whether the mesh has triangles or tetrahedra."""
    from ngsolve import VOL

    return any(el.type.name in ("TRIG", "TET") for el in mesh.Elements(VOL))


class Mixed:
    """The mixed formulation of order ``order`` on ``mesh`` with the displacement space
    ``fes`` (built with :meth:`displacement_options`): the unknown space ``fes x L2 x L2``
    (:attr:`space`), the modified energy and the guard."""

    def __init__(self, mesh, fes, order: int):
        from ngsolve import L2

        self.dim = mesh.dim
        tets = mesh.dim == 3 and has_simplices(mesh)
        self.element_space = L2(mesh, order=order - 2 if tets else order - 1)
        self.space = fes * self.element_space * self.element_space

    @staticmethod
    def displacement_options(mesh, order: int) -> dict:
        """The displacement space's options of the stable pair: the element bubble of order
        ``order + 1`` on triangles, nothing on the other elements."""
        if has_simplices(mesh):
            if order < 2:
                raise ValueError("the mixed formulation needs order >= 2 on triangles and "
                                 "tetrahedra (P1 with an element pressure locks)")
            if mesh.dim == 2:
                return {"orderinner": order + 1}
        return {}

    @staticmethod
    def split(x):
        """``(u, ϑ, p̃)`` of a trial function, test function or GridFunction of the space."""
        if hasattr(x, "components"):
            return tuple(x.components)
        return tuple(x)

    def deformation(self, G, theta):
        """``(Ḡ, J, Θ)``: ``Ḡ = F̄ - I`` with ``F̄ = (Θ/J)^(1/d) (I + G)``."""
        from ngsolve import Det, Id

        F = Id(self.dim) + G
        J = Det(F)
        Theta = 1.0 + theta
        return (Theta / J) ** (1.0 / self.dim) * F - Id(self.dim), J, Theta

    def energy(self, energy, G, theta, p, coeffs):
        """``φ(Ḡ) + p̃ (J - Θ)`` per unit reference volume, or the energy's own mixed form (its
        method ``mixed_energy``: the Wang model's,
        :meth:`~pacto_ng.physics.wang.WangModel.mixed_energy`)."""
        own = getattr(energy, "mixed_energy", None)
        if own is not None:
            return own(G, theta, p, coeffs, self)
        Gbar, J, Theta = self.deformation(G, theta)
        return energy(Gbar, coeffs) + p * (J - Theta)

    def guard(self, energy, guard, G, theta, coeffs):
        """Positive where the state is admissible: ``Θ > 0``, ``J > 0`` and the model's guard
        (if any) at ``Ḡ``; or the energy's own (its method ``mixed_guard``)."""
        from ngsolve import IfPos

        own = getattr(energy, "mixed_guard", None)
        if own is not None:
            return own(G, theta, coeffs, self)
        Gbar, J, Theta = self.deformation(G, theta)
        inner = J if guard is None else IfPos(J, guard(Gbar, coeffs), J)
        return IfPos(Theta, inner, Theta)
