"""What a part's analysis gives (:class:`~.part_analysis.PartAnalysis`): the result at one
pressure (:class:`SweepPoint`) and a sweep of them (:class:`Sweep`), with the states and
the table that analysis.json and analysis.csv are written from."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

AXES = "xyz"


@dataclass(frozen=True)
class SweepPoint:
    """The result at one pressure."""

    pressure: float
    delta: float  # output displacement Δ = Σ_k w_k d_k·u at the ports
    max_u: float  # largest |u| over the mesh vertices
    min_j: float  # smallest det(I + ∇u) over the quadrature points
    iterations: int  # Newton iterations, summed over the load steps
    converged: bool
    load_reached: float = 1.0  # fraction of the pressure at which equilibrium was found
    ports: tuple = ()  # d_k·u of every port, in the order of the analysis's ports
    vectors: tuple = ()  # every port's displacement vector (its mean over an edge or a face)
    contact_area: float | None = None  # with contact: where the walls touch (m², per wall)
    contact_force: float | None = None  # ... and the normal force between them (N)
    contact_pressure: float | None = None  # ... and the largest contact pressure (Pa)
    past_peak: bool = False  # reached by following the path past a pressure maximum
    volume_change: float | None = None  # the chamber's (m³; 2D: area × thickness); None: Darcy


@dataclass
class Sweep:
    """A sweep of one analysis kind; ``states[i]`` is the displacement vector at pressure i
    (None where it did not converge); ``analysis`` has ``mech``, ``ports`` and
    ``formulation``."""

    kind: str
    points: list
    analysis: object
    states: list = field(default_factory=list)
    #: the pressure maximum the path passed ({"pressure", "delta"}, :meth:`PartAnalysis.
    #: sweep`), None where the pressure never fell
    peak: dict | None = None
    #: the equilibria of the path past a lost equilibrium, in order ({"pressure", "delta",
    #: "volume_change"}, :meth:`PartAnalysis.sweep`)
    path: list = field(default_factory=list)

    def _arr(self, name):
        return np.array([getattr(p, name) for p in self.points])

    @property
    def pressures(self) -> np.ndarray:
        return self._arr("pressure")

    @property
    def delta(self) -> np.ndarray:
        return self._arr("delta")

    @property
    def converged(self) -> np.ndarray:
        return self._arr("converged")

    def displacement(self, i: int | None = None):
        """The displacement GridFunction at sweep point ``i`` (default: the last converged)."""
        if i is None:
            ok = [k for k, p in enumerate(self.points) if p.converged]
            if not ok:
                raise ValueError(f"the {self.kind} sweep has no converged point")
            i = ok[-1]
        if self.states[i] is None:
            raise ValueError(f"the {self.kind} analysis did not converge at point {i}")
        return self.analysis.mech.displacement_from(self.states[i])

    def contact_points(self, i: int | None = None):
        """The reference positions ``(n, dim)`` of the walls' vertices in contact (a positive
        contact pressure, :meth:`~pacto_ng.physics.contact.SelfContact.pressures`) at sweep
        point ``i`` (default: the last converged); None without contact."""
        contact = self.analysis.mech.contact
        if contact is None:
            return None
        points, pressures = contact.pressures(self.displacement(i).vec)
        return points[pressures > 0]

    def table(self) -> list[dict]:
        """One dict per pressure (for CSV/JSON): every port's ``d·u`` as ``port_<region>`` and,
        where recorded, its displacement vector as ``u_<region>_x``, ``_y`` (, ``_z``)."""
        rows = []
        for p in self.points:
            row = {k: v for k, v in p.__dict__.items() if k not in ("ports", "vectors")}
            row.update({f"port_{port.region}": v for port, v in zip(self.analysis.ports, p.ports)})
            for port, vec in zip(self.analysis.ports, p.vectors):
                row.update({f"u_{port.region}_{a}": float(c) for a, c in zip(AXES, vec)})
            rows.append(dict(kind=self.kind, **row))
        return rows
