"""cad_actuator: a pressure-actuated lever whose domain comes from a STEP file.

What it shows: a user's case file (run it by path, ``pacto run cad_actuator.py``) built only with
the public API, on a domain read from CAD with ``pn.load_cad``.  The STEP file (written by
``make_step.py``; run that first) names the face ``design`` and the left edge ``inlet``; the
rest is named here with netgen.occ selections on the loaded shape:

* ``shape.edges.Min(occ.Y)``: the bottom edge, clamped (``fixed``);
* ``shape.edges.Max(occ.X)``: the short right edge, the output (``output``);
* every edge still without a name: the zero-pressure ``skin``.

Set-up: the inlet pressure pushes on the left edge (+x); the output is the mean of -u_y over the
right edge -- the plate must turn the push into a downward stroke of its right edge, levering
on the clamped bottom edge -- against an output spring k_out; objective ``mechanism`` (minimise -Δ/SE).  E1 = 1e8 Pa,
plane strain, t = 1e-3 m, inlet pressure 1e5 Pa.

    python make_step.py                  # writes actuator.step
    pacto run cad_actuator.py            # output/cad_actuator-linear/
    pacto check-gradients cad_actuator.py
"""
from pathlib import Path

from netgen import occ

import pacto_ng as pn

STEP = Path(__file__).with_name("actuator.step")
WIDTH = 0.1   # the plate's extent along x (m), for the objective's scale


def geometry(p: pn.Parameters):
    if not STEP.is_file():
        raise pn.InputError(f"{STEP.name} not found: run 'python make_step.py' beside "
                            f"{Path(__file__).name} first")
    shape = pn.load_cad(STEP)          # face "design" and edge "inlet" come from the file
    shape.edges.Min(occ.Y).name = "fixed"
    shape.edges.Max(occ.X).name = "output"
    for edge in shape.edges:
        if not edge.name:
            edge.name = "skin"
    return shape


def setup(p: pn.Parameters) -> pn.Setup:
    return pn.Setup(
        supports=pn.Supports(clamp=("fixed",)),
        port=pn.Port("output", (0.0, -1.0), spring=p.k_out),
        pressure=pn.Pressure(inlet=("inlet",), zero=("skin", "fixed", "output")),
        objective="mechanism",
        # the typical |-Δ/SE| of a finished design (≈ 1 / (P_in W t)); scaled to 10
        objective_ref=1.0 / (p.load * WIDTH * p.thickness),
    )


CASE = pn.Case(
    name="cad_actuator",
    summary="pressure-actuated lever on an octagonal plate read from a STEP file",
    source="pacto_ng example (public API, CAD input)",
    defaults=pn.Parameters(
        model="linear", maxh=0.0035, plane="strain", thickness=1e-3, E1=1e8, E0=1e2, nu=0.4,
        volfrac=0.25, filter="helmholtz", filter_radius=0.008, penal=3.0, penal_start=1.0,
        penal_step=0.04, beta=1.0, beta_max=16.0, beta_every=15, eta_k=0.2, eta_h=0.3,
        delta_s=0.002, load=1e5, k_out=1e4, iterations=160, move=0.05, tol=0.01),
    geometry=geometry,
    setup=setup,
    load_unit="Pa",
)
