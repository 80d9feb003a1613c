"""Cantilever beam (Wang et al. 2014; thesis §5.2.2, App. D).

1.0 x 0.25 m, left edge clamped, a downward tip force at mid-height of the right edge spread
over ±2 element heights; E1 = 3e9, E0 = 3e3, ν = 0.4, t = 0.1 m, volume fraction 0.5.
Objective: end compliance F·u (``--set objective=energy`` for total strain energy).  Loads
studied: 80–500 kN (thesis limits: Neo-Hookean 150 kN, Wang 250 kN).

Its chain (``pacto run cantilever --show-chain``)::

    Embed                x -> rho
    HelmholtzFilter      rho -> rho_tilde
    HeavisideProjection  rho_tilde -> rho_proj
    FixPassive           rho_proj -> rho_bar
    Mechanics            rho_bar -> u
    LinearFunctional     u -> compliance
    Volume               rho_bar -> volume
    objective: compliance; constraints (<= 0): volume; reported: -
"""
from __future__ import annotations

import sys

from dataclasses import dataclass

from pacto_ng import Case, InputError, Parameters, PointLoad, Settings, Setup, Supports, setting
from pacto_ng.geometries import cantilever as geo


@dataclass(frozen=True)
class Options(Settings):
    """The cantilever's own settings."""

    load_width: float = setting(0.0, "m", "width of the tip patch the force is spread over (0: "
                                "4 element sizes, the case's definition)", range="[0, 0.25]")

    def check(self):
        if 0 < self.load_width < 1e-9:
            raise InputError(f"load_width: {self.load_width:g} m is no patch (0: the default of "
                             "4 element sizes)")


def _h(p: Parameters) -> float:
    return 0.25 / p.nely if p.nelx > 0 else p.maxh


def _geometry(p: Parameters):
    half = 0.5 * p.load_width if p.load_width > 0 else 2.0 * _h(p)
    return geo.layout(1.0, 0.25, load_halfwidth=half)


def _setup(p: Parameters) -> Setup:
    return Setup(supports=Supports(clamp=("fixed",)), loads=(PointLoad("load", (0.0, -1.0)),),
                 objective="compliance")


CASE = Case(
    name="cantilever",
    summary="cantilever, tip force, end compliance (linear, gnl, neohookean, wang)",
    source="Wang, Lazarov, Sigmund & Jensen (2014); thesis §5.2.2 and App. D",
    defaults=Parameters(model="linear", maxh=0.01, plane="strain", thickness=0.1, E1=3e9, E0=3e3,
                        nu=0.4, volfrac=0.5, filter="helmholtz", penal=3.0, beta=1.0,
                        beta_max=16.0, beta_every=20, load=144e3, iterations=150, tol=0.01),
    geometry=_geometry,
    setup=_setup,
    options=Options(),
    load_unit="N",
    # order 2 for linear and Wang: 0.23 % and 0.06 % from the finest objective (order 1: 1.0 %
    # and 1.23 %, docs/studies.md "Where the defaults sit"); a whole default Wang run at
    # 144 kN took 1.56x order 1's time (261 s against 167 s, one thread each, 2026-12-02).
    # Neo-Hookean and gnl keep order 1, at which the extreme-load runs were made
    model_orders={"linear": 2, "wang": 2},
)

if __name__ == "__main__":
    from pacto_ng import main

    sys.exit(main(["run", CASE.name] + sys.argv[1:]))
