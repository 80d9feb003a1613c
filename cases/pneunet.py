"""One member of a pneumatic network, PneuNet (thesis §6.3; Kumar 2023).

What it shows: an *internal* pressure load.  A chamber inside the member is pressurised; the
Darcy method (docs/theory.md §2) carries the pressure from the chamber wall to wherever the
design lets it go, and the optimiser shapes the member so that its free end bends down.

Domain 0.1 x 0.05 m (no symmetry).  A passive void chamber x ∈ [0.02, 0.08], y ∈ [0.01, 0.02]
whose boundary is the pressure inlet; zero pressure on the whole outer boundary (the clamped
left edge included).  Output: the bottom-right corner, Δ = -u_y (the member bends down), with
an output spring k_ss = k_out = 1e4 N/m (the thesis also shows 1e3).  E1 = 1e8 Pa,
E0 = 1e-6 E1, ν = 0.4, plane strain, t = 1e-3 m, volume fraction 0.2, ηk = 0.2, ηh = 0.3,
triangles of 0.0015 m; load 1e5 Pa by default (the thesis limit).  The thesis mesh (0.003 m,
``--maxh 0.003``) is 3.8 % from the finest objective of the trade study (docs/studies.md),
0.0015 m 0.19 % at 4x its time: the default.
The projection ends at β = 128 (the pressure cases' 32 left greyness 0.066: a grey layer
the part lost; at 128, 0.0065 and a part within 2 % of the design, docs/studies.md, "Per
case at defaults"), so the iteration cap is 220.

Objective ``mechanism``: minimise -sΔ/SE (thesis eq. 3.9); ``--set objective=output_se``
maximises Δ subject to SE <= se_max.  Structured quads ``--nelx 120 --nely 60``; unit elements
as for pa-inverter (see its docstring).

Its chain (``pacto run pneunet --show-chain``)::

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

from pacto_ng import Case, domain_size, Parameters
from pacto_ng.geometries import pneunet as geo


def _geometry(p: Parameters):
    L, H = domain_size(p, 0.1, 0.05)
    return geo.layout(L, H, chamber=(0.2 * L, 0.2 * H, 0.8 * L, 0.4 * H))


CASE = Case(
    name="pneunet",
    summary="PneuNet member: internal chamber pressure (Darcy), minimise -Δ/SE, bends down",
    source="Thesis §6.3; Kumar (2023); Liu et al. (2020) for PneuNets",
    defaults=Parameters(model="linear", maxh=0.0015, plane="strain", thickness=1e-3, E1=1e8,
                        E0=1e2, nu=0.4, volfrac=0.2, filter="helmholtz",
                        filter_radius=0.009, penal=3.0,
                        penal_start=1.0, penal_step=0.04, beta=1.0, beta_max=128.0,
                        beta_every=15, eta_k=0.2, eta_h=0.3, delta_s=0.002, load=1e5,
                        k_out=1e4,
                        iterations=220, move=0.05, tol=0.01,
                        obj_tol=1e-3),
    geometry=_geometry,
    setup=geo.member_setup,
    load_unit="Pa",
)

if __name__ == "__main__":
    from pacto_ng import main

    sys.exit(main(["run", CASE.name] + sys.argv[1:]))
