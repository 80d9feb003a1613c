"""five_chamber: a hand-designed 3D bending actuator, analysed as built.

What it shows: ``pacto analyse CASE --as-built`` on an actuator a designer already has (no
optimisation): a silicone finger with five internal chambers joined by a channel along its
underside, cast onto a stiffer strain-limiting bottom layer.  Inflated, the chambers push
their walls apart along the top while the bottom layer barely stretches: the finger curls
down, towards the layer.

    pacto analyse five_chamber.py --as-built --set material=ecoflex-00-30 --model yeoh \\
        --kinds follower                      # output/five_chamber-as-built/, about a minute

Geometry (metres), the half z ∈ [0, W/2] of a finger symmetric about z = 0 (``symmetry_z``,
held in z): a body 100 x 18 mm high above a 2 mm bottom layer (the solid ``stiff``: every
region named ``stiff`` takes E2, the rest E1, so this one-material case file gives the layer
its own modulus); five chambers 12 mm long, 11 mm high, 14 mm wide (7 mm in the half), 5 mm
apart, their top wall 3 mm, their side walls 3 mm; a channel 2 mm high and 4 mm wide under
them from the clamped end (where the tube enters) to the last chamber.  The chambers and the
channel are one passive void region ``chamber`` whose walls are the pressure ``inlet``.  The
clamp ``fixed`` is the end x = 0, the output ``tip`` the end x = L (Δ = the mean of -u_y over
it: the finger curls down); the other outer faces are the zero-pressure ``skin``.

Material: the body Ecoflex 00-30 (``--set material=ecoflex-00-30``: the preset's Yeoh fit,
μ0 = 34 kPa, ν = 0.45, E1 = 98.6 kPa), the layer E2 = 1 MPa (a stiffer silicone, ten times the
body; a paper or fabric layer is stiffer still: ``--set E2=...``).  Without the preset the case's
own E1 = 100 kPa and ν = 0.45 apply with the Neo-Hookean law.  Load 10 kPa; Netgen tetrahedra
of 4 mm (walls of 3 mm get smaller ones), displacement order 1 (``--order 2`` for the converged
figures, a few minutes).

The same file is also a case to optimise (the body is the ``design`` region, the layer a
passive solid, the chambers passive void): ``pacto run five_chamber.py``.
"""
from netgen import occ

import pacto_ng as pn

L, H, W = 0.1, 0.02, 0.02           # length, height (layer included), full width (m)
LAYER = 0.002                        # the strain-limiting bottom layer's thickness (m)
N, CL, GAP = 5, 0.012, 0.005          # chambers, their length and the walls between them (m)
CY0, CY1, CZ = 0.006, 0.017, 0.007    # chambers' bottom and top, their half width (m)
CH_Y0, CH_Z = 0.004, 0.002            # the channel's bottom (top = CY0) and half width (m)
X0 = L - 0.008 - N * CL - (N - 1) * GAP  # the first chamber's start: the last ends 8 mm short


def _box(x0, y0, z0, x1, y1, z1):
    return occ.Box((x0, y0, z0), (x1, y1, z1))


def geometry(p):
    """The half finger: solids ``design``, ``stiff`` and ``chamber`` (void), named faces."""
    void = _box(0.0, CH_Y0, 0.0, X0 + (N - 1) * (CL + GAP) + CL, CY0, CH_Z)
    for k in range(N):
        x = X0 + k * (CL + GAP)
        void = void + _box(x, CY0, 0.0, x + CL, CY1, CZ)
    void.solids.name = "chamber"
    void.faces.name = "inlet"
    layer = _box(0.0, 0.0, 0.0, L, LAYER, W / 2)
    layer.solids.name = "stiff"
    body = _box(0.0, LAYER, 0.0, L, H, W / 2) - void
    body.solids.name = "design"
    shape = occ.Glue([body, layer, void])
    for face in shape.faces:
        c = face.center
        if abs(c.x) < 1e-9:
            face.name = "fixed" if face.name != "inlet" else "inlet"
        elif abs(c.x - L) < 1e-9:
            face.name = "tip"
        elif abs(c.z) < 1e-9:
            face.name = "symmetry_z" if face.name != "inlet" else "inlet"
        elif face.name != "inlet" and (abs(c.y) < 1e-9 or abs(c.y - H) < 1e-9
                                       or abs(c.z - W / 2) < 1e-9):
            face.name = "skin"
    return shape


def setup(p):
    return pn.Setup(
        supports=pn.Supports(clamp=("fixed",), fix_z=("symmetry_z",)),
        pressure=pn.Pressure(inlet=("inlet",), zero=("skin", "tip")),
        port=pn.Port("tip", (0.0, -1.0, 0.0)),
        solid=("stiff",), void=("chamber",), objective="mechanism",
        objective_ref=0.1 / (p.load * L * W / 2),
    )


CASE = pn.Case(
    name="five_chamber",
    summary="hand-designed five-chamber silicone finger on a stiff layer: curls down (as built)",
    source="pacto_ng example: a PneuNet-like bending actuator (Mosadegh et al. 2014) drawn by "
           "hand, for 'pacto analyse --as-built'",
    defaults=pn.Parameters(model="neohookean", maxh=0.004, E1=1e5, E0=1e-1, E2=1e6, nu=0.45,
                           volfrac=0.5, filter_radius=0.006, load=1e4, k_out=0.0,
                           iterations=100, move=0.05),
    geometry=geometry,
    setup=setup,
    load_unit="Pa",
)
