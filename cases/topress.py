"""TOPress's base pressure-loaded structure, node for node (Kumar 2023, TOPress.m).

What it shows: our compliance next to the published pressure-load code's on its own set-up.
Read from TOPress.m (github.com/PrabhatIn/TOPress), not copied:

* mesh: nelx x nely unit square Q4 elements, plane stress, t = 1; E1 = 1, E0 = 1e-6 E1,
  ν = 0.3; SIMP E = E0 + ρ̄^p (E1 - E0); no passive elements.
* Darcy: K = Kv (1 - (1 - ε) H(ρ̄; ηf, βf)), drainage D = (ln r / Δs)² ε H(ρ̄; ηf, βf), Kv = 1,
  ε = 1e-7, r = 0.1, Δs = 2 element units, one (ηf, βf) for both; nodal forces F = -T p.
* pressure: P_in = 1 on every node of the bottom edge (its two corners included: the code
  sets the bottom edge last); p = 0 on the other nodes of the left, top and right edges.
* supports: the two bottom corner nodes, both components.
* objective: compliance UᵀKU = F·U (the load F depends on the design through p), volume
  constraint; the code's density filter is the usual normalised cone filter, as ours.

The code's call line (volfrac, rmin, ηf, βf, ...) is not in the source file; the defaults
here: volfrac 0.2, rmin 2.4, ηf 0.2, βf 10, p 3 (those of sorotop).  As sorotop, the
optimisation adds the library's penalty and projection continuation (``--set beta=0 --set
beta_max=0 --set penal_start=0``: without them, as the code; greyness 0.12 against 2e-5 with
them, 2026-12-06).

Its chain (``pacto run topress --show-chain``)::

    Embed                x -> rho
    ConeFilter           rho -> rho_tilde
    HeavisideProjection  rho_tilde -> rho_proj
    FixPassive           rho_proj -> rho_bar
    DarcyPressure        rho_bar -> p
    Mechanics            rho_bar, p -> u
    Compliance           u, p -> compliance
    Volume               rho_bar -> volume
    objective: compliance; constraints (<= 0): volume; reported: -
"""
from __future__ import annotations

import sys

from pacto_ng import Case, Parameters, Pressure, Setup, Supports
from pacto_ng.geometries import peer_codes as geo


def _geometry(p: Parameters):
    return geo.topress(p.nelx, p.nely)


def _setup(p: Parameters) -> Setup:
    return Setup(supports=Supports(clamp=("support_left", "support_right")),
                 objective="compliance",
                 pressure=Pressure(inlet=("inlet",), zero=("zero_pressure",)))


CASE = Case(
    name="topress",
    summary="TOPress.m's pressure-loaded structure, node for node (unit Q4, compliance)",
    source="Kumar (2023), TOPress, Struct Multidisc Optim 66(4); github.com/PrabhatIn/TOPress",
    defaults=Parameters(model="linear", nelx=60, nely=40, maxh=1.0, unit_elements=True,
                        plane="stress", thickness=1.0, E1=1.0, E0=1e-6, nu=0.3, volfrac=0.2,
                        filter="cone", filter_radius=2.4, load=1.0, Kv=1.0, Ks=1e-7,
                        r=0.1, delta_s=2.0, eta_k=0.2, beta_k=10.0, eta_h=0.2, beta_h=10.0,
                        move=0.1, tol=0.01),
    geometry=_geometry,
    setup=_setup,
    load_unit="Pa",
)

if __name__ == "__main__":
    from pacto_ng import main

    sys.exit(main(["run", CASE.name] + sys.argv[1:]))
