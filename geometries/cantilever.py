"""Cantilever: left edge clamped, the tip load spread over a short segment of the right edge
centred at mid-height (a point load inverts the elements under it at once)."""
from pacto_ng.mesh import Layout, Segment


def layout(width: float = 1.0, height: float = 0.25, load_halfwidth: float = 0.02) -> Layout:
    yc = 0.5 * height
    return Layout(width, height,
                  segments=(Segment("fixed", (0.0, 0.0), (0.0, height)),
                            Segment("load", (width, yc - load_halfwidth), (width, yc + load_halfwidth))),
                  points=(("tip", (width, yc)),))
