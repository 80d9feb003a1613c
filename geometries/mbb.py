"""Half MBB beam: symmetry on the left edge, roller at the bottom-right corner, load at the
top-left corner (the 88-line code's set-up)."""
from pacto_ng.mesh import Layout, Segment


def layout(width: float = 60.0, height: float = 20.0) -> Layout:
    return Layout(width, height,
                  segments=(Segment("symmetry", (0.0, 0.0), (0.0, height)),),
                  points=(("load", (0.0, height)), ("roller", (width, 0.0))))
