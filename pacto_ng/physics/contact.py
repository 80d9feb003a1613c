"""Frictionless self-contact of a body's boundary: a penalty energy on NGSolve's
``ContactBoundary``.

The candidate surface Γc (one or several named boundaries, e.g. every wall of a part) is
paired with itself (``ContactBoundary(Γc, Γc)``).  With ``X`` the reference position, ``u``
the displacement, ' the paired point and ``n`` NGSolve's contact normal (the point's outward
normal), the penetration is

    g = (X + u - (X + u)') · n        (> 0: the surfaces overlap)

and the energy ``t ∫_Γc k/2 max(g, 0)² dA`` (``t`` the thickness in 2D) joins the body's
potential: a penalty method.  Both walls of a contact belong to Γc, so each overlap is
counted from both sides: the contact pressure is ``2 k g``, and the overlap under a contact
pressure ``P`` is ``P / (2 k)``, which vanishes as ``k`` grows (tests/physics/test_contact.py
checks it against a closed form to 1e-13).  ``k`` is a multiple of the modulus over the
element size, ``E / h``, the stiffness of a layer one element deep.

Only points that face each other in the reference configuration count: their outward normals
``N``, ``N'`` more than 120° apart and the paired point in front, ``(X' - X) · N >= 0``.
Without these two conditions the walls meeting at a chamber's corner, and the two sides of a
wall thinner than the pairing distance, overlapped at u = 0 (measured on the pneunet part: a
residual of 1.5e6 N/m at zero load, and no equilibrium).

The contact pressure at a vertex of Γc (:meth:`SelfContact.pressures`) is the force the
contact energy puts on the vertex's degrees of freedom, ``f_v = ∂E/∂u_v`` (the energy's
gradient: ``BilinearForm.Apply`` of a form holding the contact energy alone), over the
vertex's share of Γc, ``t ∫_Γc φ_v dA`` with ``φ_v`` the vertex's hat function (NGSolve's H1
basis is hierarchical: a vertex's basis function is the P1 hat at any order).  Each overlap
counts once from either wall's side, and both land on the vertex, so that
``|f_v| / (t ∫ φ_v dA) = ∫ φ_v p dA / ∫ φ_v dA``, the mean of the contact pressure
``p = 2 k g`` around the vertex weighted by its hat (over all of Γc: at a corner where a wall
out of contact meets one in contact the mean counts both, and a contact zone narrower than
the vertex's elements is averaged with the wall beside it: the figure can then fall below
the mean pressure, force / area).  The largest over the vertices is the largest contact
pressure; it tends to the peak as the elements shrink (measured,
tests/physics/test_contact.py and test_hertz.py: a uniform pressure to 2e-10 in 2D and 3e-6
in 3D, where the two walls' meshes differ; Hertz's peak within -2.6e-2, -4.7e-3 and +5.4e-4
as the elements at the contact are halved once, twice and three times).

NGSolve pairs the points once per :meth:`SelfContact.update` (within ``maxdist`` of the
surface, at ``intorder`` quadrature points per face), at the state given; the pairs then stay
until the next update: the caller solves with them fixed and pairs again until they hold
(:meth:`~pacto_ng.physics.equilibrium.Equilibrium.pairs_mismatch`).  An energy that
simplifies to zero (k = 0) crashes NGSolve, so the stiffness must be positive.
"""
from __future__ import annotations

import numpy as np
from ngsolve import (H1, VERTEX, BilinearForm, CoefficientFunction, ContactBoundary,
                     GridFunction, IfPos, Integrate, LinearForm, NodeId, Parameter, ds,
                     specialcf, x, y, z)

from .walls import outward_normal

#: the cosine of the least angle between two walls' normals for them to be in contact (120°)
FACING = 0.5
#: the quadrature order on the candidate faces, by dimension: on the 3D slotted block of
#: tests/physics/test_contact.py (711 tetrahedra, linear, order 1, slot 0.02 m) order 10 took
#: 36 s (no overlap where sampled), 6 took 13 s (overlap 4.3e-6 m), 4 took 6.2 s (9.9e-5 m)
INTORDER = {2: 10, 3: 6}

#: with contact, the most pairings per solve (Newton with the pairs fixed between them): walls that
#: slide along each other settle slowly, the residual after pairing anew falling about half
#: per pairing (a Neo-Hookean slotted block loaded on its top face only, 10 kPa after 3 kPa:
#: 34 pairings, 2026-12-07)
CONTACT_CYCLES = 50
#: ... and the pairs are taken to hold once pairing anew leaves a residual below this share of
#: the load; Newton then solves once more with the new pairs, to its own tolerance.  The
#: pairing converges linearly (a residual about 0.3 times the last one per pairing on the
#: squeezed slotted slab of tests/physics/test_contact.py, every wall a candidate); against
#: pairing until 1e-10, 1e-6 moved the contact force by 1.3e-7 and Δ by 5.6e-8 of themselves,
#: in 6 pairings fewer per pressure (1213 tetrahedra, order 2, 1 and 3 kPa, 2026-12-07)
PAIRS_SETTLE = 1e-6


class PairsUnsettled(RuntimeError):
    """Pairing anew went on changing the equilibrium for :data:`CONTACT_CYCLES` pairings."""


def settle(solve, mismatch, rtol: float, close: float = PAIRS_SETTLE) -> int:
    """Solve with the pairs held, pair anew at the equilibrium, and again, until the pairs
    hold: ``solve()`` solves with the current pairs (its Newton iterations), ``mismatch()``
    pairs anew at that equilibrium and returns the residual there relative to the load.  Done
    once that is within ``rtol``, or after one more solve once it is within ``close`` (0:
    only once within ``rtol``, the pairs those of the equilibrium to Newton's tolerance, as
    central differences of a shape gradient need: tests/shape/test_contact_gradient.py).
    Returns the Newton iterations of all the solves; PairsUnsettled
    after :data:`CONTACT_CYCLES` pairings (a failed solve raises what ``solve`` raises)."""
    iterations, last = 0, False
    for _ in range(CONTACT_CYCLES):
        iterations += solve()
        if last:
            return iterations
        left = mismatch()
        if left <= rtol:
            return iterations
        last = left <= close  # one more solve, with these pairs
    raise PairsUnsettled(f"the contact's pairs did not settle in {CONTACT_CYCLES} pairings")


def element_scale(mesh) -> float:
    """``(|Ω| / elements)^(1/d)``: the element size the penalty and the pairing distance are
    measured in (the cube or square root of the mean element's measure)."""
    return float((Integrate(1.0, mesh) / mesh.ne) ** (1.0 / mesh.dim))


class SelfContact:
    """Penalty self-contact of the boundaries ``names`` of the space ``fes``'s mesh (see the
    module).

    Parameters
    ----------
    fes : ngsolve FESpace
        The state's space: the displacement's (a ``VectorH1``) or one holding it (see
        ``displacement``).
    names : tuple of str
        The candidate boundaries.
    stiffness : float
        ``k``, the penalty per unit overlap and area (Pa/m).
    maxdist : float
        Pairs are sought within this distance of the surface (a few element sizes).
    normal : CoefficientFunction, optional
        The outward unit normal on the candidate boundaries (default NGSolve's
        ``specialcf.normal``, which points into the body on some walls, e.g. those of a hole
        in 2D: give the outward one, :func:`~pacto_ng.physics.walls.outward_normal`).
    thickness : float
        The 2D thickness ``t`` (1 in 3D).
    intorder : int, optional
        The quadrature order on the candidate faces (default :data:`INTORDER`).
    displacement : callable, optional
        The displacement of a function of ``fes`` where ``fes`` holds more than it (the mixed
        formulation's state, :meth:`~pacto_ng.physics.mechanics.Mechanics.displacement`);
        default: ``fes`` is the displacement's space.
    """

    def __init__(self, fes, names, stiffness: float, maxdist: float, *, normal=None,
                 thickness: float = 1.0, intorder: int | None = None, displacement=None):
        if not stiffness > 0:
            raise ValueError(f"contact: the penalty stiffness must be positive (got {stiffness})")
        mesh = fes.mesh
        missing = [n for n in names if n not in mesh.GetBoundaries()]
        if not names or missing:
            raise ValueError(f"contact: the mesh has no boundary {missing[0] if missing else ''!r}"
                             f" (boundaries: {sorted(set(mesh.GetBoundaries()))})")
        region = mesh.Boundaries("|".join(names))
        self.names, self.maxdist = tuple(names), float(maxdist)
        self.intorder = int(intorder or INTORDER[mesh.dim])
        self.stiffness = float(stiffness)
        shift = displacement or (lambda w: w)  # the displacement of fes's functions
        self._full = GridFunction(fes)  # the state the pairs are sought at (update)
        self._moved = shift(self._full)  # its displacement: where the walls are
        ufes = self._moved.space  # the displacement's space: the measures take its vectors
        X = CoefficientFunction((x, y, z)[:mesh.dim])
        # only surfaces that face each other in the reference configuration: normals more
        # than 120° apart (two walls meeting at a corner are not in contact), and the other
        # point in front of this one, not behind it (the two sides of a thin wall)
        N = specialcf.normal(mesh.dim) if normal is None else normal
        facing = (IfPos(-(N * N.Other()) - FACING, 1.0, 0.0)
                  * IfPos((X.Other() - X) * N + 1e-6 * self.maxdist, 1.0, 0.0))

        def contact(density, u):  # a ContactBoundary with the energy density(gap) on Γc
            cb = ContactBoundary(region, region)
            cb.AddEnergy(facing * density((X + u - X.Other() - u.Other()) * cb.normal))
            return cb

        half_k = 0.5 * thickness * self.stiffness
        self.cb = contact(lambda g: IfPos(g, half_k * g * g, 0), shift(fes.TrialFunction()))
        # the measures on the displacement alone, paired once for all of them: one
        # ContactBoundary whose energy density is a0 [g > 0] + a1 g + a2 g² where g > 0, its
        # coefficients set for each measure (t/2 [g > 0] and t k g over both walls: the area
        # and the force; the contact energy, whose gradient is the nodal forces)
        w = ufes.TrialFunction()
        self._state = GridFunction(ufes)
        self._terms = (Parameter(0.0), Parameter(0.0), Parameter(0.0))
        a0, a1, a2 = self._terms
        self._measures = contact(lambda g: IfPos(g, a0 + a1 * g + a2 * g * g, 0), w)
        self._measure_form = BilinearForm(ufes)
        self._thickness = float(thickness)
        self._vertices, self._dofs, self._shares = _vertex_shares(ufes, region)

    @classmethod
    def on_walls(cls, fes, names, *, modulus: float, penalty: float, reach: float,
                 thickness: float = 1.0, displacement=None,
                 intorder: int | None = None) -> "SelfContact":
        """The walls ``names`` of a solid in self-contact: the stiffness ``penalty modulus /
        h`` and pairs sought within ``reach h`` (``h`` the mesh's :func:`element_scale`), the
        walls' outward normals (:func:`~pacto_ng.physics.walls.outward_normal`)."""
        mesh, names = fes.mesh, tuple(names)
        h = element_scale(mesh)
        return cls(fes, names, penalty * float(modulus) / h, reach * h,
                   normal=outward_normal(mesh, "|".join(names)), thickness=thickness,
                   displacement=displacement, intorder=intorder)

    def measure(self, vec) -> tuple[float, float, float]:
        """``(area, force, pressure)`` of the contact at the displacement ``vec`` (a vector of
        the displacement's space, as the measures below): the area of either
        wall where they overlap (in 2D the length times the thickness), the normal force
        between them, ``2 k ∫ max(g, 0)`` over one wall (times the thickness in 2D), and the
        largest contact pressure, the largest of :meth:`pressures` (0 without contact); one
        pairing."""
        self._pair_measures(vec)
        t, k = self._thickness, self.stiffness
        return (self._measured(0.5 * t, 0.0), self._measured(0.0, t * k),
                float(self._pressures().max(initial=0.0)))

    def overlap(self, vec) -> float:
        """The area of either wall where the walls overlap at the displacement ``vec`` (in 2D the
        length times the thickness): :meth:`measure`'s first figure, one pairing."""
        self._pair_measures(vec)
        return self._measured(0.5 * self._thickness, 0.0)

    def overlap_depth(self, vec) -> tuple[float, float]:
        """``(area, depth)``: :meth:`overlap`, and the mean depth over which the walls overlap
        at the displacement ``vec`` (0 where they do not), ``∫ max(g, 0) / ∫ [g > 0]`` over
        the walls; one pairing."""
        self._pair_measures(vec)
        area = self._measured(0.5 * self._thickness, 0.0)
        force = self._measured(0.0, self._thickness * self.stiffness)
        return area, (force / (2.0 * self.stiffness * area) if area > 0 else 0.0)

    def _pair_measures(self, vec) -> None:
        """Pair the measures' surface at the displacement ``vec``."""
        self._state.vec.data = vec
        self._measures.Update(self._state, self._measure_form, intorder=self.intorder,
                              maxdist=self.maxdist)

    def _measured(self, a0: float, a1: float, a2: float = 0.0) -> float:
        """The measures' energy with the coefficients ``a0, a1, a2`` (the last pairing's)."""
        for term, value in zip(self._terms, (a0, a1, a2)):
            term.Set(value)
        return float(self._measure_form.Energy(self._state.vec))

    def pressures(self, vec) -> tuple[np.ndarray, np.ndarray]:
        """``(points, p)`` at the displacement ``vec``: the reference positions of Γc's vertices
        (an array ``(n, dim)``) and the contact pressure at each, the hat-weighted mean of
        ``2 k max(g, 0)`` around it (see the module; 0 where the walls do not touch)."""
        self._pair_measures(vec)
        return self._vertices.copy(), self._pressures()

    def _pressures(self) -> np.ndarray:
        """The contact pressure at Γc's vertices at the displacement ``self._state`` (the
        last pairing's)."""
        for term, value in zip(self._terms, (0.0, 0.0, 0.5 * self._thickness * self.stiffness)):
            term.Set(value)
        f = self._state.vec.CreateVector()
        self._measure_form.Apply(self._state.vec, f)
        nodal = f.FV().NumPy()[self._dofs]  # (vertices, dim): the force on each vertex
        return np.linalg.norm(nodal, axis=1) / (self._thickness * self._shares)

    def update(self, form, vec) -> None:
        """Pair the candidate surface with itself at the state ``vec`` (a vector of ``fes``)
        and register the contact energy with the BilinearForm ``form``."""
        self._full.vec.data = vec
        self.cb.Update(self._moved, form, intorder=self.intorder, maxdist=self.maxdist)


def _vertex_shares(fes, region) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(points, dofs, shares)`` of the vertices of the boundary ``region`` of ``fes``'s mesh:
    their positions ``(n, dim)``, the displacement's degrees of freedom at each ``(n, dim)``
    (the vertex's hat function in every component of the VectorH1) and ``∫_region φ_v dA``,
    the integral of the vertex's hat function over the region."""
    mesh = fes.mesh
    hats = H1(mesh, order=1)
    share = LinearForm(hats)
    share += hats.TestFunction() * ds(definedon=region)
    share.Assemble()
    weights = share.vec.FV().NumPy()
    points, dofs, shares = [], [], []
    for v in mesh.vertices:
        w = weights[hats.GetDofNrs(NodeId(VERTEX, v.nr))[0]]
        if w > 0:
            points.append(v.point)
            dofs.append(fes.GetDofNrs(NodeId(VERTEX, v.nr)))
            shares.append(w)
    return (np.array(points, dtype=float).reshape(-1, mesh.dim),
            np.array(dofs, dtype=int).reshape(-1, mesh.dim), np.array(shares, dtype=float))
