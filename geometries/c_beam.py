"""C-beam (Yoon et al. 2005): a 10 x 10 m square with a C-shaped solid of 1 m thick top,
bottom and left arms; the rest void.  Left edge clamped; f1 at the free end of the top arm,
f2 at the free end of the bottom arm."""
from pacto_ng.mesh import Layout, Region, Segment


def layout(size: float = 10.0, arm: float = 1.0, loads_on: str = "points") -> Layout:
    """``fixed`` left edge, material ``void`` inside the C, load regions ``f1`` (top arm's
    free end) and ``f2`` (bottom arm's free end) as corner points (``loads_on="points"``) or
    as the arms' end edges (``loads_on="edges"``)."""
    segs = [Segment("fixed", (0.0, 0.0), (0.0, size))]
    pts = ()
    if loads_on == "points":
        pts = (("f1", (size, size)), ("f2", (size, 0.0)))
    elif loads_on == "edges":
        segs += [Segment("f1", (size, size - arm), (size, size)),
                 Segment("f2", (size, 0.0), (size, arm))]
    else:
        raise ValueError("loads_on must be 'points' or 'edges'")
    return Layout(size, size, segments=tuple(segs),
                  regions=(Region("void", "void", arm, arm, size, size - arm),), points=pts)
