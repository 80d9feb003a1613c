"""A straight silicone finger, written as a user would: geometry, supports, pressure, port,
material, load and volume fraction only -- no mesh size, filter, schedule or optimiser
setting.  The numerical settings are derived from the case (pacto_ng.derive.derive_settings;
``pacto run tests/cases/user_finger.py --show-parameters`` says how each came about).

An 80 x 16 mm finger, 15 mm wide out of plane, cast in Dragon Skin 30, clamped at its base
(the left edge); a slot chamber along its middle whose wall is the pressure inlet (10 kPa),
zero pressure on the outer skin; the tip's lower corner should move down against a 1000 N/m
spring (the object it presses on; about 0.08 of the finger's E1 t, as pneunet-silicone's).
"""
from netgen import occ

import pacto_ng as pn

LENGTH, HEIGHT = 0.08, 0.016      # finger length and height (m)
SLOT = (0.012, 0.050, 0.003)      # chamber from x0 to x1 (m), its height (m), centred in y


def geometry(p):
    body = (occ.WorkPlane().MoveTo(0, 0)
            .LineTo(LENGTH, 0, name="skin")
            .LineTo(LENGTH, HEIGHT, name="skin")
            .LineTo(0, HEIGHT, name="skin")
            .LineTo(0, 0, name="base")
            .Face())
    x0, x1, h = SLOT
    chamber = occ.WorkPlane().MoveTo(x0, (HEIGHT - h) / 2).Rectangle(x1 - x0, h).Face()
    chamber.edges.name = "inlet"
    chamber.faces.name = "chamber"
    design = body - chamber
    design.faces.name = "design"
    shape = occ.Glue([design, chamber])
    shape.vertices.Nearest((LENGTH, 0, 0)).name = "tip"
    return shape


def setup(p):
    return pn.Setup(
        supports=pn.Supports(clamp=("base",)),
        pressure=pn.Pressure(inlet=("inlet",), zero=("skin", "base")),
        port=pn.Port("tip", (0.0, -1.0), spring=1000.0),
        void=("chamber",),
        objective="mechanism",
    )


CASE = pn.Case(
    name="user-finger",
    summary="straight silicone finger, slot chamber, the tip bends down (a user's case)",
    source="tests/cases/user_finger.py",
    # how much material the finger may have: 30 % of it (at the declared 20 % the optimiser
    # leaves one-element members towards the tip that the part loses: its tip moved 75 % less
    # than the design's, measured)
    defaults=pn.Parameters(material="dragonskin-30", thickness=0.015, load=1e4, volfrac=0.3),
    geometry=geometry,
    setup=setup,
    load_unit="Pa",
)
