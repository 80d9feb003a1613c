"""Design-independent loads and springs, written as potential terms ``Π_ext(u)``.

Forces are *totals* in newtons (they are not multiplied by the thickness): a
:class:`PointLoad` acts at every mesh vertex of a named point region or is spread uniformly
over a named boundary (so that a "point" load does not invert the elements under it), a
:class:`Spring` resists the displacement component along ``direction`` at a named
point (``k/2 (d·u)²``) or, on a named boundary, its mean over that boundary.  The
Darcy pressure loads live in :mod:`pacto_ng.physics.darcy_load`.

Regions by dimension: in 2D a named point (a vertex region) or a named boundary edge; in 3D a
named point (a vertex region), a named edge (its mean over the edge's length) or a named face
(its mean over the face's area).  Forces and directions have as many components as the mesh
has dimensions (``ValueError`` otherwise).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from ngsolve import BBBND, BBND, BND, CF, IfPos, Integrate, ds, dx, exp, x, y, z

from ..settings import Settings, setting
from .walls import solid_boundaries


@dataclass(frozen=True)
class LoadSettings(Settings):
    """The load's magnitude and the output spring of the cases."""

    load: float = setting(1.0, "N", "load magnitude (force in N, or inlet pressure in Pa); "
                          "positive: the case's force directions and inlet set the sign",
                          range="[1e-20, 1e30]")
    k_out: float = setting(0.0, "N/m", "output spring stiffness", range="[0, 1e30]")


def _region(mesh, name):
    """``(region, kind)`` of a named point (``"point"``) or boundary: in 2D a named edge
    (``"boundary"``); in 3D a named face (``"boundary"``) or a named edge (``"edge"``)."""
    points = mesh.BBBoundaries if mesh.dim == 3 else mesh.BBoundaries
    if name in named_points(mesh):
        return points(name), "point"
    if mesh.dim == 3 and name in mesh.GetBBoundaries():
        return mesh.BBoundaries(name), "edge"
    if name in mesh.GetBoundaries():
        return mesh.Boundaries(name), "boundary"
    raise ValueError(f"port '{name}' is neither a named point nor a boundary of the mesh")


def _measure(mesh, name):
    """``(measure, weight)``: a point's measure and weight 1 (the value at its vertices), or a
    boundary's (an edge's in 3D) measure and one over its length or area (the mean over it)."""
    reg, kind = _region(mesh, name)
    if kind == "point":
        return dx(definedon=reg), 1.0
    size = Integrate(1.0, mesh, definedon=reg)
    if size <= 0:
        raise ValueError(f"boundary '{name}' is empty")
    return (ds(definedon=reg) if kind == "boundary" else dx(definedon=reg)), 1.0 / size


def _vector(mesh, values, what: str, region: str):
    """``values`` as a CF of the mesh's dimension (``ValueError`` if the length differs)."""
    if len(values) != mesh.dim:
        raise ValueError(f"{what} at '{region}': {len(values)} components on a {mesh.dim}D mesh "
                         f"(give {mesh.dim})")
    return CF(tuple(float(v) for v in values))


@dataclass(frozen=True)
class PointLoad:
    """Total force ``force`` (N) at a named point or spread uniformly over a named boundary."""

    region: str
    force: tuple[float, ...]

    def work(self, mesh, u, scale=1.0):
        """``scale · F·u`` as an integral (``scale`` may be a Parameter)."""
        force = _vector(mesh, self.force, "force", self.region)
        meas, w = _measure(mesh, self.region)
        return (scale * w * (force * u)) * meas


#: a spread spring's weight exp(-ρ²/spread²) is cut to zero at ρ = SPREAD_REACH spreads (a
#: weight of 1.1e-7 there)
SPREAD_REACH = 4.0


@dataclass(frozen=True)
class Spring:
    """Linear spring ``k/2 (d·u)²`` at a named point (or on the mean of a boundary), N/m;
    ``direction`` has as many components as the mesh has dimensions (the default is 2D's x).

    ``spread`` > 0 (m) spreads a spring at a named point over the boundary near it: the
    weighted mean ``k/2 ∫_Γ ω (d·u)² ds / ∫_Γ ω ds`` over the solid's boundaries, with the
    weight ``ω = exp(-|x - x0|² / spread²)`` about the point ``x0``, cut to zero beyond
    SPREAD_REACH spreads (:meth:`support`, a ball a shape refinement holds).  A force at a
    point has no finite displacement in elasticity (it grows as the mesh under it is refined,
    in 2D as the logarithm of the element size), so a point spring's Δ depends on the mesh:
    on a body-fitted part, whose elements at a corner port are smaller than the design's,
    the spring's force can crush the element at the point.  A spread spring, the size of
    what the port pushes on, acts alike on the design's mesh and on the part's where the
    port's neighbourhood is the solid's boundary in both (not a passive void's edge).
    """

    region: str
    stiffness: float
    direction: tuple[float, ...] = (1.0, 0.0)
    spread: float = 0.0

    def weight(self, mesh):
        """``(ω, measure, size)``: the spring's weight, the measure it integrates over and
        ``∫ ω`` over it: 1, the point's measure and 1; 1, the edge's or the boundary's and its
        length or area; spread about a point, the weight of the class docstring, the solid's
        boundaries (not the interfaces between its domains: :func:`~pacto_ng.physics.walls.
        solid_boundaries`) and ``∫ ω ds`` (summed over the ranks of a distributed mesh)."""
        support = self.support(mesh)
        if support is None:
            meas, w = _measure(mesh, self.region)
            return CF(1.0), meas, 1.0 / w
        x0, reach = support
        r2 = sum((c - float(v)) ** 2 for c, v in zip((x, y, z), x0))
        omega = exp(-r2 / self.spread ** 2) * IfPos(reach ** 2 - r2, 1.0, 0.0)
        names = solid_boundaries(mesh)
        region = mesh.Boundaries(names[0])
        for name in names[1:]:
            region = region + mesh.Boundaries(name)
        return omega, ds(definedon=region), float(Integrate(omega, mesh, BND, definedon=region))

    def support(self, mesh):
        """``(x0, radius)``: the ball about the point ``x0`` out of which the weight of a
        spread spring is zero; None for a spring that is not spread about a point."""
        if not self.spread > 0 or _region(mesh, self.region)[1] != "point":
            return None
        return point_of(mesh, self.region), SPREAD_REACH * self.spread

    def energy(self, mesh, u):
        """``k/2 (d·u)²`` as an integral: at the point, or the ω-weighted mean over the
        boundary (:meth:`weight`).  For a boundary or a spread spring it is the mean square, a
        distributed spring of the same total stiffness, not the squared mean (as stated in
        the docs); at a point both agree."""
        d = np.asarray(self.direction, dtype=float)
        d = _vector(mesh, d / np.linalg.norm(d), "spring direction", self.region)
        omega, meas, size = self.weight(mesh)
        return (0.5 * self.stiffness / size) * omega * (d * u) ** 2 * meas

    def where(self, mesh):
        """The region of the mesh the spring acts on (a point, an edge or a boundary)."""
        return _region(mesh, self.region)[0]


def named_points(mesh) -> tuple[str, ...]:
    """The names of the mesh's named points (vertex regions)."""
    return tuple(mesh.GetBBBoundaries() if mesh.dim == 3 else mesh.GetBBoundaries())


def point_of(mesh, name: str) -> tuple[float, ...]:
    """The coordinates of the named point ``name`` (its first vertex)."""
    for el in mesh.Elements(BBBND if mesh.dim == 3 else BBND):
        if el.mat == name:
            return tuple(mesh[el.vertices[0]].point)
    raise ValueError(f"'{name}' is not a named point of the mesh")


@dataclass(frozen=True)
class Port:
    """Where a response reads the displacement: ``weight · d·u`` at a named point (or the mean
    over a named boundary).  ``spring`` > 0 adds an output spring ``spring/2 (d̂·u)²`` there
    (d̂ the unit direction), the work piece a mechanism pushes against.  Several ports (e.g.
    the two jaws of a gripper) add up to one output ``Δ = Σ weight · d·u``."""

    region: str
    direction: tuple[float, ...]
    spring: float = 0.0
    weight: float = 1.0
    spread: float = 0.0  # the spring's spread about a named point (Spring.spread), m

    def __post_init__(self):
        if not self.spring >= 0:
            raise ValueError(f"port '{self.region}': spring must be >= 0 (got {self.spring})")
        if not np.isfinite(self.weight) or self.weight == 0:
            raise ValueError(f"port '{self.region}': weight must be finite and non-zero "
                             f"(got {self.weight})")

    def functional(self, mesh, u):
        direction = _vector(mesh, self.direction, "port direction", self.region)
        meas, w = _measure(mesh, self.region)
        return (self.weight * w) * (direction * u) * meas

    def springs(self) -> tuple[Spring, ...]:
        """The port's output spring (none for ``spring`` = 0)."""
        return ((Spring(self.region, self.spring, self.direction, self.spread),)
                if self.spring > 0 else ())


@dataclass(frozen=True)
class Outputs:
    """Several output ports read as one output ``Δ = Σ weight_i d_i·u_i``."""

    ports: tuple[Port, ...]

    def functional(self, mesh, u):
        total = None
        for port in self.ports:
            term = port.functional(mesh, u)
            total = term if total is None else total + term
        return total
