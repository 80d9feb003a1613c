"""A 3D cantilever: a beam clamped at one end, a downward traction on the other (compliance).

What it shows: the chain on Netgen tetrahedra, and the solver studies' model problem
(docs/studies.md, "3D solvers").  Beam 1.0 x 0.25 x 0.125 m, the face x = 0 clamped, a
total downward force ``load`` (N) spread uniformly over the end face x = 1.0.  E1 = 3e9 Pa,
E0 = 1e-6 E1, ν = 0.4, volume fraction 0.3, tetrahedra of 0.02 m, Helmholtz filter of radius
0.06 m (three elements).  Objective: end compliance F·u; linear by default, ``--model wang``
for large deflections (the load then matters: 1e5 N by default).  Measured 2026-12-07 with
``PACTO_THREADS=1 pacto run cantilever-3d --model wang``: converged at iteration 141,
compliance 1.427e4, greyness 0.042, 7 min on one thread (docs/studies.md "The design path").
``--model neohookean`` stalls at this load: by iteration 22 (p 1.88, β 1) a design takes
122 Newton iterations (70 s).  Not because the void crushes (that design's equilibrium has its
lowest det F at 0.92), but because Newton's full steps overshoot on the grey, soft beam, which
deflects 28 % of its length there (docs/studies.md, "Neo-Hookean runs in 3D").

Continuation: the library's (p 1 -> 3, β 1 -> 64, each β stage ending once settled).  Measured
2026-12-06 with ``pacto run cantilever-3d``: converged at iteration 123 (β = 64 from 110),
compliance 1.327e4, greyness 0.026, one connected part reaching the loaded end; 42 s.  The
case's earlier β 1 -> 16 on tetrahedra of 0.03 m (the filter two elements wide) ended at
greyness 0.138 (compliance 1.531e4), and the same projection to 64 on that mesh made a part
in two pieces that stopped 0.11 m short of the loaded end.

Its chain (``pacto run cantilever-3d --show-chain``)::

    Embed                x -> rho
    HelmholtzFilter      rho -> rho_tilde
    HeavisideProjection  rho_tilde -> rho_proj
    FixPassive           rho_proj -> rho_bar
    Mechanics            rho_bar -> u
    LinearFunctional     u -> compliance
    Volume               rho_bar -> volume
    objective: compliance; constraints (<= 0): volume; reported: -
"""
from __future__ import annotations

import sys

from pacto_ng import Case, Parameters, PointLoad, Setup, Supports
from pacto_ng.geometries import solids

LENGTH, HEIGHT, DEPTH = 1.0, 0.25, 0.125


def _geometry(p: Parameters):
    return solids.cantilever(LENGTH, HEIGHT, DEPTH)


def _setup(p: Parameters) -> Setup:
    return Setup(supports=Supports(clamp=("fixed",)),
                 loads=(PointLoad("load", (0.0, -1.0, 0.0)),), objective="compliance")


CASE = Case(
    name="cantilever-3d",
    summary="3D cantilever, end-face traction, compliance (linear, gnl, neohookean, wang)",
    source="the 2D cantilever's set-up (Wang, Lazarov, Sigmund & Jensen 2014) in 3D",
    defaults=Parameters(model="linear", maxh=0.02, E1=3e9, E0=3e3, nu=0.4, volfrac=0.3,
                        filter="helmholtz", filter_radius=0.06, load=1e5),
    geometry=_geometry,
    setup=_setup,
    load_unit="N",
)

if __name__ == "__main__":
    from pacto_ng import main

    sys.exit(main(["run", CASE.name] + sys.argv[1:]))
