"""Pressure-actuated compliant gripper (thesis §6.2; Kumar, Frouws & Langelaar 2020).

What it shows: a pressure-driven gripper whose jaw closes on an object.  The Darcy method
(docs/theory.md §2) decides where the pressure acts; the optimiser turns the inlet pressure
into a jaw motion towards the symmetry line.

The pa-inverter domain (half 0.2 x 0.1 m, inlet on the left edge, zero pressure on the top and
right edges, clamp and passive solid block at the top-left corner) with a passive void
x ∈ [0.8L, L], y ∈ [0, 0.2H] (the gripped object's place) and a passive solid jaw pad
x ∈ [0.8L, L], y ∈ [0.2H, 0.25H].  Output: the inner right corner of the jaw pad (L, 0.2H),
Δ = -u_y (the jaw closes) with an output spring k_ss = k_out = 1e4 N/m.  E1 = 3e9 Pa,
E0 = 1e-6 E1, ν = 0.4, plane strain, t = 1e-3 m, volume fraction 0.2, triangles of 0.002 m;
load 1e6 Pa by default (the thesis ran 1e5–1e7 Pa).  The thesis mesh (0.004 m, Table 6.1,
``--maxh 0.004``) is 2.9 % from the finest objective of the trade study (docs/studies.md),
0.002 m 0.17 % at 4x its time: the default.

Objective ``mechanism``: minimise -sΔ/SE (thesis eq. 3.9); ``--set objective=output_se``
maximises Δ subject to SE <= se_max.  Structured quads and the unit-element set-up as for
pa-inverter (see its docstring).

Its chain (``pacto run pa-gripper --show-chain``)::

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
from pacto_ng.derive import PRESSURE_DEFAULTS
from pacto_ng.geometries import pa_mechanism as geo


def _geometry(p: Parameters):
    L, H = domain_size(p, 0.2, 0.1)
    return geo.layout(L, H, gripper=True)


CASE = Case(
    name="pa-gripper",
    summary="pressure-actuated gripper (Darcy pressure), minimise -Δ/SE, the jaw closes",
    source="Thesis §6.2 (Table 6.1); Kumar, Frouws & Langelaar (2020), Struct Multidisc Optim 61",
    defaults=PRESSURE_DEFAULTS.replace(maxh=0.002),
    geometry=_geometry,
    setup=geo.gripper_setup,
    load_unit="Pa",
)

if __name__ == "__main__":
    from pacto_ng import main

    sys.exit(main(["run", CASE.name] + sys.argv[1:]))
