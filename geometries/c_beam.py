"""C-beam (Yoon et al. 2005): a 10 x 10 m square with a C-shaped solid of 1 m thick top,
bottom and left arms; the rest void.  Left edge clamped; f1 at the free end of the top arm,
f2 at the free end of the bottom arm."""
from pacto_ng.mesh import Layout, Region, Segment


def layout(size: float = 10.0, arm: float = 1.0) -> Layout:
    return Layout(size, size,
                  segments=(Segment("fixed", (0.0, 0.0), (0.0, size)),),
                  regions=(Region("void", "void", arm, arm, size, size - arm),),
                  points=(("f1", (size, size)), ("f2", (size, 0.0))))
