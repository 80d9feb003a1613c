"""A 3D PneuNet member: a chamber inside a block, clamped at one end; the free end bends down.

What it shows: an internal pressure load in 3D.  Block 0.1 x 0.05 x 0.03 m (L x H x D), the
2D pneunet's cross-section given a depth; the chamber x ∈ [0.02, 0.08], y ∈ [0.01, 0.02]
spans the middle two thirds of the depth, and its walls are the pressure inlet.  Solved on
the half z ∈ [0, D/2] (``symmetry_z`` held in z, no flux through it).  The face x = 0 is
clamped; zero pressure on every outer face (the clamped one and the end face included).
Output: the end face x = L, Δ = the mean of -u_y over it (the member bends down), with an
output spring of k_out on the same mean, 1.5e5 N/m for the half (the 2D case's 1e4 N/m per mm
of depth).  E1 = 1e8 Pa, E0 = 1e-6 E1, ν = 0.4, volume fraction 0.25, tetrahedra of 0.0025 m
(18 473; at 0.004 m, 4395, six elements through the half-depth left the design grey, greyness
0.16 against 0.10, and made it a quarter as good, -Δ/SE -2.4e-3 against -4.4e-3, measured
2026-12-03), Helmholtz filter of radius 0.01 m, load 1e5 Pa.  Objective ``mechanism``:
minimise -sΔ/SE.  A wall one element thick (``inlet_wall`` 2.5 mm) is kept solid around the
chamber: without it the optimiser opened the chamber through a chimney to the side face
(the Darcy pressure pushes on the chimney's grey walls), greyness 0.098, its part not sealed.

Continuation: p 1 → 3 by 0.04, then β 1 → 32, each β stage ending once settled (its last five
objective changes below 0.3 %) or after 30 iterations, up to 300 iterations.  Measured
2026-12-06 (`PACTO_THREADS=1 pacto run pneunet-3d`): converged at iteration 113 (-4.07e-3),
greyness 0.045, sealed, the part 16.6 µm against the design's 19.8 µm at order 2 (-16.3 %);
51 s + 16 s for the part.

Its chain (``pacto run pneunet-3d --show-chain``)::

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

import sys

from pacto_ng import Case, Parameters, Port, Pressure, Setup, Spring, Supports
from pacto_ng.derive import se_default
from pacto_ng.geometries import solids

LENGTH, HEIGHT, DEPTH = 0.1, 0.05, 0.03


def _geometry(p: Parameters):
    return solids.pneunet(LENGTH, HEIGHT, DEPTH)


def _setup(p: Parameters) -> Setup:
    volume = LENGTH * HEIGHT * 0.5 * DEPTH
    return Setup(supports=Supports(clamp=("fixed",), fix_z=("symmetry_z",)),
                 springs=(Spring("tip", p.k_out, (0.0, 1.0, 0.0)),),
                 port=Port("tip", (0.0, -1.0, 0.0)), void=("chamber",), objective="mechanism",
                 pressure=Pressure(inlet=("inlet",), zero=("zero_pressure", "fixed", "tip")),
                 se_max=se_default(p, volume),
                 # -Δ/SE is of order 0.1 / (P_in L D/2), as the 2D case's 0.1 / (P_in L t)
                 objective_ref=0.1 / (p.load * LENGTH * 0.5 * DEPTH))


CASE = Case(
    name="pneunet-3d",
    summary="3D PneuNet member: internal chamber pressure (Darcy), minimise -Δ/SE, bends down",
    source="the 2D pneunet (thesis §6.3; Kumar 2023) given a depth; Mosadegh et al. (2014) "
           "for PneuNets",
    defaults=Parameters(model="linear", maxh=0.0025, E1=1e8, E0=1e2, nu=0.4, volfrac=0.25,
                        filter="helmholtz", filter_radius=0.01, penal=3.0, penal_start=1.0,
                        penal_step=0.04, beta=1.0, beta_max=32.0, beta_every=30,
                        beta_settle=3e-3, eta_k=0.2, eta_h=0.3, delta_s=0.002, load=1e5,
                        k_out=1.5e5,
                        inlet_wall=0.0025,
                        iterations=300, move=0.05,
                        tol=0.01, obj_tol=1e-3),
    geometry=_geometry,
    setup=_setup,
    load_unit="Pa",
)

if __name__ == "__main__":
    from pacto_ng import main

    sys.exit(main(["run", CASE.name] + sys.argv[1:]))
