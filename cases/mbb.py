"""Half MBB beam — the classic benchmark of the 88-line code (Andreassen et al. 2011).

Unit square elements (structured nelx x nely), E = 1, E0 = 1e-9, ν = 0.3, plane stress, unit
load at the top-left corner, symmetry on the left edge, roller at the bottom-right corner;
volume fraction 0.5, cone density filter of radius 1.5 elements.  The 88-line code's
optimisation (p = 3 throughout, no projection: ``--set penal=3 --set beta=0 --set move=0.2``)
ends grey: its published compliance for 60 x 20 is about 218.8, and this case with those
settings reached 210.7 at greyness 0.197.  By default the case takes the library's penalty and
projection continuation (p 1 -> 3, β 1 -> 64): the design ends crisp, at greyness 4e-5 and
compliance 187.2 after 101 iterations (``pacto run mbb``, measured 2026-12-06).

Its chain (``pacto run mbb --show-chain``)::

    Embed                x -> rho
    ConeFilter           rho -> rho_tilde
    HeavisideProjection  rho_tilde -> rho_proj
    FixPassive           rho_proj -> rho_bar
    Mechanics            rho_bar -> u
    LinearFunctional     u -> compliance
    Volume               rho_bar -> volume
    objective: compliance; constraints (<= 0): volume; reported: -
"""
from __future__ import annotations

import sys

from pacto_ng import Case, Parameters, PointLoad, Setup, Supports
from pacto_ng.geometries import mbb as geo


def _geometry(p: Parameters):
    if p.nelx > 0:  # unit elements
        return geo.layout(float(p.nelx), float(p.nely))
    return geo.layout(60.0, 20.0)


def _setup(p: Parameters) -> Setup:
    return Setup(supports=Supports(fix_x=("symmetry",), fix_y=("roller",)),
                 loads=(PointLoad("load", (0.0, -1.0)),), objective="compliance")


CASE = Case(
    name="mbb",
    summary="half MBB beam, compliance, 88-line code set-up (unit elements, plane stress)",
    source="Andreassen et al. (2011), Efficient topology optimization in MATLAB using 88 lines of code",
    defaults=Parameters(model="linear", nelx=60, nely=20, maxh=1.0, plane="stress", thickness=1.0,
                        E1=1.0, E0=1e-9, nu=0.3, volfrac=0.5, filter="cone", filter_radius=1.5,
                        load=1.0),
    geometry=_geometry,
    setup=_setup,
    load_unit="N",
)

if __name__ == "__main__":
    from pacto_ng import main

    sys.exit(main(["run", CASE.name] + sys.argv[1:]))
