"""Write ``actuator.step`` beside this script: the CAD half of the ``cad_actuator`` example.

What it shows: a 2D part drawn in CAD (here with netgen.occ; any CAD program that writes STEP
will do) and saved as a STEP file, the form in which a design domain usually arrives.  The part
is an octagonal plate 0.1 m across; its face is named ``design`` and its left edge ``inlet`` in
the file (netgen.occ writes the names of faces and edges into STEP and reads them back).  The
other names the optimisation needs -- the clamps, the output, the zero-pressure skin -- are
given afterwards, in the case file ``cad_actuator.py``, by selecting the edges by position.

    python make_step.py            # writes actuator.step next to this file
    pacto run cad_actuator.py      # then optimise
"""
from pathlib import Path

from netgen import occ

#: the outline, counter-clockwise; the closing edge (0, 0.03) -> (0, -0.03) is the inlet
OUTLINE = [(0.0, -0.03), (0.04, -0.05), (0.07, -0.05), (0.10, -0.01),
           (0.10, 0.01), (0.07, 0.05), (0.04, 0.05), (0.0, 0.03)]


def make_shape():
    wp = occ.WorkPlane().MoveTo(*OUTLINE[0])
    for point in OUTLINE[1:]:
        wp.LineTo(*point)
    wp.LineTo(*OUTLINE[0], name="inlet")
    face = wp.Face()
    face.name = "design"
    return face


if __name__ == "__main__":
    path = Path(__file__).with_name("actuator.step")
    make_shape().WriteStep(str(path))
    print(f"wrote {path}")
