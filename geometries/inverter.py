"""Force inverter, half domain (symmetry at y = 0): input at the left end of the symmetry line
(spread over ``input_height``), output at the right end, clamp on the top of the left edge."""
from pacto_ng.mesh import Layout, Segment


def layout(width: float = 150e-6, height: float = 75e-6, clamp: float = 7.5e-6,
           input_height: float = 3e-6) -> Layout:
    return Layout(width, height,
                  segments=(Segment("symmetry", (0.0, 0.0), (width, 0.0)),
                            Segment("input", (0.0, 0.0), (0.0, input_height)),
                            Segment("fixed", (0.0, height - clamp), (0.0, height))),
                  points=(("output", (width, 0.0)), ("input_point", (0.0, 0.0))))
