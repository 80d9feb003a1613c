"""Two-material pressure-actuated compliant gripper (thesis §6.4; Pinskier, Kumar et al. 2023).

What it shows: the pa-gripper with two design fields (thesis eq. 6.1, Sigmund & Torquato 1997):
``E = (1-ρ̄1^p) E0 + ρ̄1^p [(1-ρ̄2^p) E1 + ρ̄2^p E2]``, ρ̄1 = solid or void, ρ̄2 = soft (0) or
stiff (1) material.  The optimiser places the stiff material where the gripper needs stiffness
and the soft one where it must bend.

Layout, supports, pressure and output as pa-gripper (half 0.2 x 0.1 m, Δ = -u_y at the jaw pad
corner, k_ss = 1e4 N/m).  E1 = 3e8 Pa (soft), E2 = 3e9 Pa (stiff), E0 = 1e-6 E1; ν = 0.4,
plane strain, t = 1e-3 m.  Volume constraints: the total solid ρ̄1 <= 0.2 (docs/theory.md §6)
and, by default, the stiff-material field ρ̄2 <= 0.1 of the design domain (``volfrac2``).  The
thesis lists only the first; without the second the optimum is stiff material everywhere but a
few hinge elements (measured at the thesis mesh: soft material 0.1 % of the domain, stiff
19.7 %), so "two materials" would show nothing.  ``--set volfrac2=0`` gives the thesis formulation.
The Darcy pressure sees the total solid ρ̄1.  Passive solids (clamp block, jaw pad) are of the
stiff material.  Load 5e5 Pa by default (the thesis limit of its Neo-Hookean model).
Triangles of 0.002 m: the thesis mesh (0.004 m, ``--maxh 0.004``) is 1.9 % from the finest
objective of the trade study (docs/studies.md), 0.002 m 1.0 % at 4.6x its time.
β doubles every 7 iterations (final problem from iteration 85 of 160) and the move limit is
0.1: with the pa-inverter's every 15 and 0.05 (final from 125) the objective still fell by
0.1-0.4 % per iteration at the cap, −0.0939; every 10 and 0.1 reached −0.103 at the cap, still
falling by about 0.1 % per iteration; every 8 and 0.1 the same (−0.1037, the last 4 changes below
1e-3 at the cap); every 7 and 0.1 converged at iteration 151, −0.1030 (one run each,
docs/studies.md, "Convergence at defaults", measured 2026-12-03).

Its chain (``pacto run mm-gripper --show-chain``)::

    Slice                x -> x1
    Slice                x -> x2
    Embed                x1 -> rho1
    HelmholtzFilter      rho1 -> rho_tilde1
    HeavisideProjection  rho_tilde1 -> rho_proj1
    FixPassive           rho_proj1 -> rho_bar1
    Embed                x2 -> rho2
    HelmholtzFilter      rho2 -> rho_tilde2
    HeavisideProjection  rho_tilde2 -> rho_proj2
    FixPassive           rho_proj2 -> rho_bar2
    DarcyPressure        rho_bar1 -> p
    Mechanics            rho_bar1, rho_bar2, p -> u
    LinearFunctional     u -> delta
    StrainEnergy         u, rho_bar1, rho_bar2, p -> se
    MechanismRatio       delta, se -> objective
    Volume               rho_bar1 -> volume
    Volume               rho_bar2 -> volume2
    objective: objective; constraints (<= 0): volume, volume2; reported: delta, se
"""
from __future__ import annotations

import dataclasses
import sys

from pacto_ng import Case, domain_size, Parameters, Setup
from pacto_ng.derive import PRESSURE_DEFAULTS
from pacto_ng.geometries import pa_mechanism as geo


def _geometry(p: Parameters):
    L, H = domain_size(p, 0.2, 0.1)
    return geo.layout(L, H, gripper=True)


def _setup(p: Parameters) -> Setup:
    return dataclasses.replace(geo.gripper_setup(p), materials=2)


CASE = Case(
    name="mm-gripper",
    summary="two-material pressure-actuated gripper (E1 soft, E2 stiff), minimise -Δ/SE",
    source="Thesis §6.4 (eq. 6.1); Pinskier, Kumar et al. (2023); Sigmund & Torquato (1997)",
    defaults=PRESSURE_DEFAULTS.replace(maxh=0.002, E1=3e8, E2=3e9, E0=3e2, load=5e5,
                                 volfrac2=0.1, beta_every=7, move=0.1),
    geometry=_geometry,
    setup=_setup,
    load_unit="Pa",
)

if __name__ == "__main__":
    from pacto_ng import main

    sys.exit(main(["run", CASE.name] + sys.argv[1:]))
