"""A PneuNet-style bending segment cast in silicone, in real units (docs/guide.md, "Silicone
cases").

What it shows: one segment of a pneumatic-network bender as it would be cast: a 40 x 15 mm
section, 15 mm wide out of plane, in Dragon Skin 30 (the ``dragonskin-30`` preset of
pacto_ng/physics/presets.py: its published Yeoh fit, μ0 = 307 kPa), under a 10 kPa chamber
pressure that follows the deforming walls (a follower load).  The pressure bends the free end
down.

Domain 40 x 15 mm, clamped on the left edge.  A passive void chamber x ∈ [15, 25] mm,
y ∈ [3.75, 8.25] mm whose boundary is the pressure inlet; zero pressure on the whole outer
boundary.  Output: the bottom-right corner, Δ = -u_y, with an output spring k_out = 1000 N/m
(about 0.1 of the segment's E1 t, as the pneunet case's 1e4 N/m against its 1e5 N/m).  Model:
Wang's interpolation over the preset's Yeoh law; ν = 0.45 (the preset's) and
``formulation=auto``, which takes the mixed formulation there (Q1/P0) against volumetric
locking.  Structured quadrilaterals of 0.5 mm (80 x 30), Darcy penetration depth Δs = 1 mm,
filter radius 2 mm, volume fraction 0.4, β doubled every 10 iterations once the penalty
reaches 3 (every 15: still at the move limit after 160 iterations), up to 64.  Load 10 kPa:
p/E1 = 1.1e-2, 11 times the pneunet's.  A wall one element thick is kept solid around the
chamber (``inlet_wall`` 0.5 mm).  Measured 2026-12-06 (`PACTO_THREADS=1 pacto run
pneunet-silicone`): converged at iteration 124, greyness 0.013, sealed, the part 0.170 mm
against the design's 0.189 mm (-10.3 %); 136 s + 7.6 s for the part.  Before (β to 32, no
wall): greyness 0.024 and the chamber open to the outer boundary.

Why this chamber and volume: with a 20 x 6 mm chamber and volume fraction 0.3 the optimiser
thinned the chamber's walls to a one- or two-element membrane that balloons (its top wall moved
12 mm at 10 kPa), and Newton lost the follower equilibrium every few iterations, at 0.29-0.95
of the load (docs/guide.md, "Silicone cases", has the measurements).

Its chain (``pacto run pneunet-silicone --show-chain``)::

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

from pacto_ng import Case, domain_size, Parameters, Setup
from pacto_ng.geometries import pneunet as geo

WIDTH, HEIGHT = 0.04, 0.015


def _geometry(p: Parameters):
    L, H = domain_size(p, WIDTH, HEIGHT)
    return geo.layout(L, H, chamber=(0.375 * L, 0.25 * H, 0.625 * L, 0.55 * H))


def _setup(p: Parameters) -> Setup:
    return geo.member_setup(p, WIDTH, HEIGHT, 0.24)


CASE = Case(
    name="pneunet-silicone",
    summary="PneuNet-style segment in Dragon Skin 30, mm scale, 10 kPa follower chamber "
            "pressure: bends down",
    source="pneunet (thesis §6.3) at real scale; the preset's source in presets.py",
    defaults=Parameters(model="wang", material="dragonskin-30", nelx=80, nely=30,
                        plane="strain", thickness=0.015, volfrac=0.4,
                        filter="helmholtz", filter_radius=0.002, penal=3.0, penal_start=1.0,
                        penal_step=0.04, beta=1.0, beta_max=64.0, beta_every=10, eta_k=0.2,
                        eta_h=0.3, delta_s=0.001, load=1e4, k_out=1000.0,
                        load_type="follower", iterations=160, move=0.05, tol=0.01,
                        obj_tol=1e-3, inlet_wall=0.0005),
    geometry=_geometry,
    setup=_setup,
    load_unit="Pa",
)

if __name__ == "__main__":
    from pacto_ng import main

    sys.exit(main(["run", CASE.name] + sys.argv[1:]))
