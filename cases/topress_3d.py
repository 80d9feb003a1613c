"""TOPress3D's pressure-loaded compliance set-up on its structured hexahedra, node for node
(Kumar 2024, TOPress3D.m).

What it shows: our 3D compliance under a Darcy pressure load next to the published code's, on
its own grid.  Read from TOPress3D.m (github.com/PrabhatIn/TOPress3D), not copied; the paper:
P. Kumar (2024), TOPress3D: 3D topology optimization with design-dependent pressure loads in
MATLAB, Optimization and Engineering, doi:10.1007/s11081-024-09931-2:

* mesh: nelx x nely x nelz unit cubes, trilinear 8-node hexahedra (H8, 2x2x2 Gauss), the
  domain [0, nelx] x [0, nely] x [0, nelz]; the code numbers its nodes y fastest (counted
  from y = nely down), then z, then x, and its elements likewise; no passive elements.
* material: E1 = 1, E0 = 1e-5 E1 (note: not TOPress's 1e-6), ν = 0.3, 3D elasticity;
  SIMP E = E0 + ρ̄^p (E1 - E0).
* Darcy: K = Kv (1 - (1 - ε) H(ρ̄; ηf, βf)), drainage D = (ln r / Δs)² ε H(ρ̄; ηf, βf), Kv = 1,
  ε = 1e-7, r = 0.1, Δs = 2 element units, one (ηf, βf) for both (here Ks = Kv ε, eta_k =
  eta_h = ηf, beta_k = beta_h = βf); element matrices: the H8 Laplace and mass matrices.
* pressure: P_in = 1 on every node of the face z = nelz (the code's "top" face, its rim
  included); p = 0 on every node of the face z = 0; no flux through the four side faces.
* load: nodal forces F = -T p with T[3a+c, b] = ∫ N_a ∂N_b/∂x_c (the body force -∇p).
* supports: the nodes on the rim of the face z = nelz (where it meets x = 0, x = nelx,
  y = 0, y = nely), all three components.
* objective: the compliance Uᵀ K U = F·U (F depends on the design through p), with the load
  sensitivity (the code's lst = 1); constraint Σρ̄ / (nel volfrac) - 1 <= 0.
* filter: the normalised cone (density) filter of radius rmin in element units, weights
  max(0, rmin - |d|) between element centres (the code's imfilter with zero padding,
  normalised by the filtered ones); ρ̄ is the filtered density, no projection.

The code's call line (volfrac, penal, rmin, ηf, βf, maxit) is not in the source file; the
defaults here: a 16 x 16 x 8 grid, volfrac 0.2, p 3, rmin 2.4, ηf 0.2, βf 10 (those of
topress).  As topress, the optimisation adds the library's penalty and projection
continuation (``--set beta=0 --set beta_max=0 --set penal_start=0``: without them, as the code;
greyness 0.42 against 0.023 with them, 2026-12-06).  The design is a bowl that hangs from the
clamped rim and sags to mid-depth at the centre: P_in above it, p = 0 below; its part is the
piece pinned at the rim's nodes.
The optimiser is ours (MMA then GCMMA, move 0.1), not the code's MMA set-up, so designs agree
in kind, not iterate for iterate; the analysis of a given ρ̄ agrees to round-off
(tests/cases/test_topress_3d.py against tests/topress3d_reference.py).

The geometry is a :class:`~pacto_ng.box.Box` of ``nelx x nely x nelz`` unit cubes meshed as
structured hexahedra: patches "inlet" (the whole face z = nelz) and "zero_pressure" (the whole
face z = 0), and the rim's nodes as points all named "rim" (a Box names faces and points, not
edges).

Its chain (``pacto run topress-3d --show-chain``)::

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

from pacto_ng import Case, InputError, Parameters, Pressure, Setup, Supports
from pacto_ng.box import Box, Patch


def rim_points(nelx: int, nely: int, nelz: int) -> tuple:
    """The nodes where the face z = nelz meets the four side faces, each a point "rim"."""
    return tuple(("rim", (float(i), float(j), float(nelz)))
                 for i in range(nelx + 1) for j in range(nely + 1)
                 if i in (0, nelx) or j in (0, nely))


def _geometry(p: Parameters):
    if min(p.nelx, p.nely, p.nelz) < 2:
        raise InputError("topress-3d: TOPress3D's grid of unit cubes needs --nelx, --nely and "
                         "--nelz, each at least 2 (structured hexahedra)")
    return Box(float(p.nelx), float(p.nely), float(p.nelz),
               patches=(Patch("inlet", "zmax"), Patch("zero_pressure", "zmin")),
               points=rim_points(p.nelx, p.nely, p.nelz))


def _setup(p: Parameters) -> Setup:
    return Setup(supports=Supports(clamp=("rim",)), objective="compliance",
                 pressure=Pressure(inlet=("inlet",), zero=("zero_pressure",)))


CASE = Case(
    name="topress-3d",
    summary="TOPress3D.m's pressure-loaded compliance set-up, node for node (unit H8 cubes)",
    source="Kumar (2024), TOPress3D, Optim Eng, doi:10.1007/s11081-024-09931-2; "
           "github.com/PrabhatIn/TOPress3D",
    defaults=Parameters(model="linear", nelx=16, nely=16, nelz=8, maxh=1.0, order=1,
                        E1=1.0, E0=1e-5, nu=0.3, volfrac=0.2, filter="cone", filter_radius=2.4,
                        load=1.0, Kv=1.0, Ks=1e-7, r=0.1, delta_s=2.0, eta_k=0.2,
                        beta_k=10.0, eta_h=0.2, beta_h=10.0, move=0.1, tol=0.01),
    geometry=_geometry,
    setup=_setup,
    load_unit="Pa",
)

if __name__ == "__main__":
    from pacto_ng import main

    sys.exit(main(["run", CASE.name] + sys.argv[1:]))
