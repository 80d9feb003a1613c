"""Soft finger: a tapered finger with a round pressure chamber that curls its tip down.

What it shows (a copyable example of the public API, ``import pacto_ng as pn`` and netgen.occ
only): a non-rectangular domain drawn with ``occ.WorkPlane`` -- a finger that tapers from a
base of height ``BASE`` to a round tip of height ``TIP`` -- with a passive void chamber cut out
of it and glued back in as a face of its own, named edges (the clamped base, the outer skin),
a named vertex (the output port at the tip), and an internal Darcy pressure load: the
chamber's wall is the pressure inlet, the whole outer skin is at zero pressure, so the
optimiser has to keep a sealed cavity around the chamber and shape the skin around it so that
the inflating cavity curls the finger down.

Set-up: the base (left edge) clamped; output port at the tip, Δ = -u_y (the tip moves down,
towards the flat "palm" side) against an output spring k_out; objective ``mechanism``
(minimise -Δ/SE).  E1 = 1e8 Pa (as the PneuNet case; a silicone would be ~1e6 Pa with a
hyperelastic model), plane strain, t = 1e-3 m, inlet pressure 1e5 Pa.  A wall of 1.6 mm
(one element) is kept solid around the chamber (``inlet_wall``), and β goes to 64.  Measured
2026-12-06 (`PACTO_THREADS=1 pacto run soft-finger`): converged at iteration 148, greyness
0.015, sealed, the part's tip 1.68 µm down against the design's 2.01 µm at order 2
(-16.7 %); 10 s.  Without the wall the optimiser opened the chamber towards the skin and
its design's 17 µm came from the Darcy load on the opening's grey walls: its part moved
0.63 µm (-96 %).

    pacto run soft-finger                      # output/soft-finger-linear/
    pacto check-gradients soft-finger
    pacto analyse output/soft-finger-linear    # threshold, remesh, re-analysis

Its chain (``pacto run soft-finger --show-chain``)::

    Embed                x -> rho
    HelmholtzFilter      rho -> rho_tilde
    HeavisideProjection  rho_tilde -> rho_proj
    FixPassive           rho_proj -> rho_bar
    DarcyPressure        rho_bar -> p
    Mechanics            rho_bar, p -> u
    LinearFunctional     u -> delta
    StrainEnergy         u, rho_bar, p -> se
    MechanismRatio       delta, se -> objective
    Volume               rho_bar -> volume
    objective: objective; constraints (<= 0): volume; reported: delta, se
"""
from __future__ import annotations

from netgen import occ

import pacto_ng as pn

LENGTH = 0.10      # base to tip (m)
BASE = 0.026       # height at the clamped base (m)
TIP = 0.012        # height at the round tip (m)
CHAMBER = (0.032, 0.011, 0.006)   # centre x, centre y and radius of the round chamber (m)


def geometry(p: pn.Parameters):
    """The finger as named netgen.occ faces, edges and a vertex."""
    r = TIP / 2
    body = (occ.WorkPlane().MoveTo(0, 0)
            .LineTo(LENGTH - r, 0, name="skin")       # flat underside (the palm side)
            .Arc(r, 180, name="skin")                 # round tip
            .LineTo(0, BASE, name="skin")             # tapered back
            .LineTo(0, 0, name="base")                # clamped base
            .Face())
    cx, cy, cr = CHAMBER
    chamber = occ.WorkPlane().Circle(cx, cy, cr).Face()
    chamber.edges.name = "inlet"       # the pressure enters through the chamber wall
    chamber.faces.name = "chamber"     # passive void
    design = body - chamber
    design.faces.name = "design"
    shape = occ.Glue([design, chamber])
    shape.vertices.Nearest((LENGTH - r, 0, 0)).name = "tip"   # underside meets the round tip
    return shape


def setup(p: pn.Parameters) -> pn.Setup:
    return pn.Setup(
        supports=pn.Supports(clamp=("base",)),
        port=pn.Port("tip", (0.0, -1.0), spring=p.k_out),
        void=("chamber",),
        pressure=pn.Pressure(inlet=("inlet",), zero=("skin", "base")),
        objective="mechanism",
        # the typical |-Δ/SE| of a finished design (≈ 0.5 / (P_in L t)); scaled to 10
        objective_ref=0.5 / (p.load * LENGTH * p.thickness),
    )


CASE = pn.Case(
    name="soft-finger",
    summary="tapered soft finger, round pressure chamber, minimise -Δ/SE, the tip curls down",
    source="pacto_ng example (public API)",
    defaults=pn.Parameters(
        model="linear", maxh=0.0016, plane="strain", thickness=1e-3, E1=1e8, E0=1e2, nu=0.4,
        volfrac=0.3, filter="helmholtz", filter_radius=0.004, penal=3.0, penal_start=1.0,
        penal_step=0.04, beta=1.0, beta_max=64.0, beta_every=15, eta_k=0.2, eta_h=0.3,
        delta_s=0.002, load=1e5, k_out=1e4, iterations=200, move=0.05, tol=0.01,
        obj_tol=1e-3, inlet_wall=0.0016),
    geometry=geometry,
    setup=setup,
    load_unit="Pa",
)

