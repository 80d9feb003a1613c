"""The output displacement a run reports (summary.json's ``output_displacement`` and
``output_displacement_at``) where its chain does not compute it: ``Δ = Σ weight · d·u`` at the
case's output ports or, without one, at its one point/edge load in the force's direction."""
from __future__ import annotations

import numpy as np

from .physics.loads import Outputs, Port
from .problem import Problem
from .responses import output_displacement as output_block


def _output_ports(problem: Problem) -> tuple:
    """What the reported output displacement reads, and whether that is the case's ports:
    its ports, or else a unit-direction port at its one point/edge load (empty: neither)."""
    setup = problem.setup
    if setup.ports:
        return setup.ports, "port"
    if len(setup.loads) == 1:
        force = np.asarray(setup.loads[0].force, dtype=float)
        norm = float(np.linalg.norm(force))
        if norm > 0:
            return (Port(setup.loads[0].region, tuple(force / norm)),), "load"
    return (), None


def output_displacement(problem: Problem) -> float | None:
    """``Δ = Σ weight · d·u`` of the last analysed state (see :func:`output_displacement_at`),
    for a run whose chain does not compute it.  None before any analysis or where the case has
    neither a port nor a single point/edge load."""
    vals = problem.values
    ports, _ = _output_ports(problem)
    if "u" not in vals or not ports:
        return None
    where = ports[0] if len(ports) == 1 else Outputs(ports)
    return output_block(problem.mech, where).forward(vals["u"])


def output_displacement_at(problem: Problem) -> dict | None:
    """Where the output displacement is read: ``kind`` "port" (the case's output ports) or
    "load" (no port: at its one point/edge load, in the force's direction), and each
    ``region`` with its ``direction`` d and ``weight`` (Δ = Σ weight · d·u, u at a named point
    or its mean over a named boundary).  None where no output displacement is defined."""
    ports, kind = _output_ports(problem)
    if not ports:
        return None
    return {"kind": kind,
            "terms": [{"region": port.region, "direction": [float(c) for c in port.direction],
                       "weight": float(port.weight)} for port in ports]}
