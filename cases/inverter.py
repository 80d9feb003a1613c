"""Force-driven displacement inverter (thesis §5.2.3, Table 5.4).

Half domain 150 x 75 µm (symmetry at y = 0), t = 7 µm, E1 = 3e9, E0 = 3e3, ν = 0.3, volume
fraction 0.2.  Input force in +x at the left end of the symmetry line (spread over two element
heights) with an input spring k_in = 4000 N/m; output at the right end with k_out = 40 N/m;
clamp on the top 7.5 µm of the left edge.  Objective: maximise -u_x at the output (it moves
against the input).

Its chain (``pacto run inverter --show-chain``)::

    Embed                x -> rho
    HelmholtzFilter      rho -> rho_tilde
    HeavisideProjection  rho_tilde -> rho_proj
    FixPassive           rho_proj -> rho_bar
    Mechanics            rho_bar -> u
    LinearFunctional     u -> delta
    Scale                delta -> objective
    Volume               rho_bar -> volume
    objective: objective; constraints (<= 0): volume; reported: delta
"""
from __future__ import annotations

import sys

from dataclasses import dataclass

from pacto_ng import (Case, InputError, Parameters, PointLoad, Port, Settings, Setup, Spring,
                      Supports, setting)
from pacto_ng.geometries import inverter as geo


@dataclass(frozen=True)
class Options(Settings):
    """The inverter's own settings."""

    load_width: float = setting(0.0, "m", "height of the input the force is spread over (0: 2 "
                                "element sizes, the case's definition)", range="[0, 7.5e-5]")
    k_in: float = setting(4000.0, "N/m", "input spring stiffness", range="[0, 1e30]")

    def check(self):
        if 0 < self.load_width < 1e-12:
            raise InputError(f"load_width: {self.load_width:g} m is no patch (0: the default of "
                             "2 element sizes)")


def _h(p: Parameters) -> float:
    return 75e-6 / p.nely if p.nelx > 0 else p.maxh


def _geometry(p: Parameters):
    height = p.load_width if p.load_width > 0 else 2.0 * _h(p)
    return geo.layout(150e-6, 75e-6, clamp=7.5e-6, input_height=height)


def _setup(p: Parameters) -> Setup:
    return Setup(supports=Supports(clamp=("fixed",), fix_y=("symmetry",)),
                 loads=(PointLoad("input", (1.0, 0.0)),),
                 springs=(Spring("input", p.k_in, (1.0, 0.0)), Spring("output", p.k_out, (1.0, 0.0))),
                 port=Port("output", (-1.0, 0.0)), objective="output")


CASE = Case(
    name="inverter",
    summary="force inverter, input/output springs, maximise the inverted output displacement",
    source="Thesis §5.2.3 (Table 5.4); Bendsøe & Sigmund (2003) inverter",
    defaults=Parameters(model="linear", maxh=1.5e-6, plane="strain", thickness=7e-6, E1=3e9,
                        E0=3e3, nu=0.3, volfrac=0.2, filter="helmholtz", penal=3.0, beta=1.0,
                        beta_max=16.0, beta_every=25, load=0.1, k_out=40.0,
                        iterations=200, tol=0.01),
    geometry=_geometry,
    setup=_setup,
    options=Options(),
    load_unit="N",
)

if __name__ == "__main__":
    from pacto_ng import main

    sys.exit(main(["run", CASE.name] + sys.argv[1:]))
