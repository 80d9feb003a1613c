"""One member of a pneumatic network (docs/theory.md §6, "pneunet"): an internal chamber
(passive void "chamber", default x ∈ [0.02, 0.08], y ∈ [0.01, 0.02]) whose boundary is the
pressure inlet "inlet"; the left edge "fixed" (clamped), the rest of the outer boundary
"zero_pressure"; port "output" at the bottom-right corner.  The case puts zero pressure on the
*whole* outer boundary (docs/theory.md §6): a boundary has one name, so the case lists both
"zero_pressure" and "fixed" as zero-pressure boundaries."""
from pacto_ng.derive import mechanism_scales
from pacto_ng.mesh import Layout, Region, Segment
from pacto_ng.params import Parameters
from pacto_ng.physics.loads import Port, Spring
from pacto_ng.physics.mechanics import Supports
from pacto_ng.setup import Pressure, Setup


def layout(width: float = 0.1, height: float = 0.05,
           chamber: tuple[float, float, float, float] = (0.02, 0.01, 0.08, 0.02)) -> Layout:
    L, H = width, height
    return Layout(L, H,
                  segments=(Segment("fixed", (0.0, 0.0), (0.0, H)),
                            Segment("zero_pressure", (0.0, 0.0), (L, 0.0)),
                            Segment("zero_pressure", (L, 0.0), (L, H)),
                            Segment("zero_pressure", (L, H), (0.0, H))),
                  regions=(Region("chamber", "void", *chamber, boundary="inlet"),),
                  points=(("output", (L, 0.0)),))


def member_setup(p: Parameters, width: float = 0.1, height: float = 0.05,
                 ratio: float = 0.1) -> Setup:
    """The member's set-up on its ``width`` x ``height`` domain (geometries/pneunet.py's
    layout), ``ratio`` the objective's typical magnitude
    (:func:`pacto_ng.derive.objective_ref`): the set-up of the cases on this layout (pneunet,
    pneunet-silicone)."""
    se_max, objective_ref = mechanism_scales(p, width, height, ratio)
    return Setup(supports=Supports(clamp=("fixed",)),
                 springs=(Spring("output", p.k_out, (0.0, 1.0)),),
                 port=Port("output", (0.0, -1.0)), void=("chamber",), objective="mechanism",
                 pressure=Pressure(inlet=("inlet",), zero=("zero_pressure", "fixed")),
                 se_max=se_max, objective_ref=objective_ref)
