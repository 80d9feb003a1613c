"""SoRoTop's base pressure-actuated mechanism, node for node (Kumar 2023, SoRoTop.m).

What it shows: our number next to the published soft-robot code's on its own set-up.  Read
from SoRoTop.m (github.com/PrabhatIn/SoRoTop), not copied:

* mesh: nelx x nely unit square Q4 elements, plane stress, t = 1; E1 = 1, E0 = 1e-6 E1,
  ν = 0.3; SIMP E = E0 + ρ̄^p (E1 - E0).
* Darcy: K = Kv (1 - (1 - ε) H(ρ̄; ηf, βf)) and drainage D = (ln r / Δs)² ε H(ρ̄; ηf, βf)
  with Kv = 1, ε = 1e-7, r = 0.1, Δs = 2 element units, one (ηf, βf) for both; nodal forces
  F = -T p with T the element matrix ∫ N_i ∂N_j (our body force -∇p).
* pressure: P_in = 1 on every node of the left edge (its two corners included: the code sets
  the left edge last); p = 0 on the top edge's other nodes and on the right edge's; no flux
  through the bottom edge (the symmetry line).
* supports: the first floor(nely/20) nodes of the top edge from the left corner clamped (2
  nodes at nely = 40: x = 0 and x = 1; the code counts them with nely, not nelx); u_y = 0 on
  the bottom edge.
* passive solid: the top floor(nely/20) rows x left floor(nelx/20) columns of elements.
* output: u_x of the bottom-right node with a spring kss = k_out; the code minimises u_x
  (Δ = -u_x here) subject to a volume and a strain-energy limit: objective ``output_se``.

What the code does that this case does not: the robust min-max over a blueprint (η = 0.5)
and an eroded (η = 0.5 + δ) design with the strain-energy limit on the eroded one, and that
limit relative (``sefrac`` times the start design's ½UᵀKU, which counts the output spring's
½ kss u_out² as well); here the limit is ``se_max`` in units of the element energy of the
spring-free structure (default: ``SEFRAC`` times the measured start-design energy at 60 x 40).
The code's filter applies the transpose of the normalised cone-weight matrix (Hsᵀ x); ours is
the usual normalised filter (Hs x).  The analysis of a given ρ̄ -- pressure, loads,
displacements, Δ, SE -- is the code's (tests/cases/test_peer_setups.py checks it to 1e-10).

The code's call line (volfrac, sefrac, rmin, kss, ηf, βf, ...) is not in the source file; the
defaults here are this project's peer benchmark's (benchmarks/peer_pa_inverter.py): rmin 2.4,
kss 0.1, ηf 0.2, βf 10, p 3, volfrac 0.2.  The optimisation adds what the library gives a case
that sets none (``--show-parameters``): the penalty from 1 to 3 and a projection of the design
with β doubled to 64, so that the design is crisp and its part holds pressure and moves as
designed.  ``--set beta=0 --set beta_max=0 --set penal_start=0`` runs without them, as the code
(no projection, p = 3 throughout): greyness 0.19 and the part 23.7 % short of its design
(2026-12-06, docs/benchmarks.md), against 0.0007 and -6.4 % with them.

Its chain (``pacto run sorotop --show-chain``)::

    Embed                x -> rho
    ConeFilter           rho -> rho_tilde
    HeavisideProjection  rho_tilde -> rho_proj
    FixPassive           rho_proj -> rho_bar
    DarcyPressure        rho_bar -> p
    Mechanics            rho_bar, p -> u
    LinearFunctional     u -> delta
    Scale                delta -> objective
    StrainEnergy         u, rho_bar, p -> se
    Bound                se -> se_limit
    Volume               rho_bar -> volume
    objective: objective; constraints (<= 0): volume, se_limit; reported: delta, se
"""
from __future__ import annotations

import sys

from pacto_ng import Case, Parameters, Port, Pressure, Setup, Spring, Supports
from pacto_ng.geometries import peer_codes as geo

#: strain-energy limit as a fraction of the start design's energy (the code's sefrac; the
#: start design ρ̄ = volfrac with the block solid stores START_SE at 60 x 40 (188161 = 78.4 x
#: 2400, ``pacto evaluate sorotop`` on that field), in units of P_in² t nelx nely / E1)
SEFRAC = 0.1
START_SE = 78.4


def _geometry(p: Parameters):
    return geo.sorotop(p.nelx, p.nely)


def _setup(p: Parameters) -> Setup:
    se_unit = p.load ** 2 * p.nelx * p.nely * p.thickness / p.E1
    clamp, zero = geo.sorotop_names(p.nely)
    return Setup(supports=Supports(clamp=clamp, fix_y=("symmetry",)),
                 springs=(Spring("output", p.k_out, (1.0, 0.0)),),
                 port=Port("output", (-1.0, 0.0)), solid=("block",),
                 objective="output_se",
                 pressure=Pressure(inlet=("inlet",), zero=("zero_pressure",) + zero),
                 se_max=SEFRAC * START_SE * se_unit)


CASE = Case(
    name="sorotop",
    summary="SoRoTop.m's pressure-actuated mechanism, node for node (unit Q4, max -u_x, SE limit)",
    source="Kumar (2023), SoRoTop, Optimization and Engineering; github.com/PrabhatIn/SoRoTop",
    defaults=Parameters(model="linear", nelx=60, nely=40, maxh=1.0, unit_elements=True,
                        plane="stress", thickness=1.0, E1=1.0, E0=1e-6, nu=0.3, volfrac=0.2,
                        filter="cone", filter_radius=2.4, load=1.0, k_out=0.1,
                        Kv=1.0, Ks=1e-7, r=0.1, delta_s=2.0, eta_k=0.2, beta_k=10.0, eta_h=0.2,
                        beta_h=10.0, move=0.1, tol=0.01),
    geometry=_geometry,
    setup=_setup,
    load_unit="Pa",
)

if __name__ == "__main__":
    from pacto_ng import main

    sys.exit(main(["run", CASE.name] + sys.argv[1:]))
