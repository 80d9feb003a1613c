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

from ..settings import Settings, setting


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
    named_points = mesh.GetBBBoundaries() if mesh.dim == 3 else mesh.GetBBoundaries()
    if name in named_points:
        return points(name), "point"
    if mesh.dim == 3 and name in mesh.GetBBoundaries():
        return mesh.BBoundaries(name), "edge"
    if name in mesh.GetBoundaries():
        return mesh.Boundaries(name), "boundary"
    raise ValueError(f"port '{name}' is neither a named point nor a boundary of the mesh")


def _measure(mesh, name):
    """``(measure, weight)``: a point's measure and weight 1 (the value at its vertices), or a
    boundary's (an edge's in 3D) measure and one over its length or area (the mean over it)."""
    from ngsolve import Integrate, dx, ds

    reg, kind = _region(mesh, name)
    if kind == "point":
        return dx(definedon=reg), 1.0
    size = Integrate(1.0, mesh, definedon=reg)
    if size <= 0:
        raise ValueError(f"boundary '{name}' is empty")
    return (ds(definedon=reg) if kind == "boundary" else dx(definedon=reg)), 1.0 / size


def _vector(mesh, values, what: str, region: str):
    """``values`` as a CF of the mesh's dimension (``ValueError`` if the length differs)."""
    from ngsolve import CF

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


@dataclass(frozen=True)
class Spring:
    """Linear spring ``k/2 (d·u)²`` at a named point (or on the mean of a boundary), N/m;
    ``direction`` has as many components as the mesh has dimensions (the default is 2D's x)."""

    region: str
    stiffness: float
    direction: tuple[float, ...] = (1.0, 0.0)

    def energy(self, mesh, u):
        d = np.asarray(self.direction, dtype=float)
        d = _vector(mesh, d / np.linalg.norm(d), "spring direction", self.region)
        meas, w = _measure(mesh, self.region)
        # the mean displacement of a boundary needs the squared mean, not the mean square:
        # for a point region w = 1 and both agree; for an edge we use the mean square (a
        # distributed spring of the same total stiffness), which is stated in the docs.
        return 0.5 * self.stiffness * w * (d * u) ** 2 * meas

    def where(self, mesh):
        """The region of the mesh the spring acts on (a point, an edge or a boundary)."""
        return _region(mesh, self.region)[0]


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
        return (Spring(self.region, self.spring, self.direction),) if self.spring > 0 else ()


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
