"""One member of a pneumatic network (docs/theory.md §6, "pneunet"): an internal chamber
(passive void "chamber", default x ∈ [0.02, 0.08], y ∈ [0.01, 0.02]) whose boundary is the
pressure inlet "inlet"; the left edge "fixed" (clamped), the rest of the outer boundary
"zero_pressure"; port "output" at the bottom-right corner.  The case puts zero pressure on the
*whole* outer boundary (docs/theory.md §6): a boundary has one name, so the case lists both
"zero_pressure" and "fixed" as zero-pressure boundaries."""
from pacto_ng.mesh import Layout, Region, Segment


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
