"""A 3D cantilever: a beam clamped at one end, a downward traction on the other (compliance).

What it shows: the chain on Netgen tetrahedra, and the solver studies' model problem
(docs/studies.md, "3D solvers").  Beam 1.0 x 0.25 x 0.125 m, the face x = 0 clamped, a
total downward force ``load`` (N) spread uniformly over the end face x = 1.0.  E1 = 3e9 Pa,
E0 = 1e-6 E1, ν = 0.4, volume fraction 0.3, tetrahedra of 0.03 m, Helmholtz filter of radius
0.06 m.  Objective: end compliance F·u; linear by default, ``--model neohookean`` or ``wang``
for large deflections (the load then matters: 1e5 N by default).

Continuation: β 1 → 16, each stage ending once settled (its last five compliance changes
below 0.3 %) or after 20 iterations, up to 200 iterations.  Measured 2026-12-03
(docs/studies.md, "3D cases at defaults"): with β every 20 and 100 iterations the run
stopped at the cap still moving by the move limit (compliance 1.565e4); 200 iterations
converge at 178 (1.531e4), the settled stages at 165 (1.531e4).
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
    defaults=Parameters(model="linear", maxh=0.03, E1=3e9, E0=3e3, nu=0.4, volfrac=0.3,
                        filter="helmholtz", filter_radius=0.06, penal=3.0, beta=1.0,
                        beta_max=16.0, beta_every=20, beta_settle=3e-3, load=1e5, iterations=200,
                        tol=0.01),
    geometry=_geometry,
    setup=_setup,
    load_unit="N",
)

if __name__ == "__main__":
    from pacto_ng import main

    sys.exit(main(["run", CASE.name] + sys.argv[1:]))
