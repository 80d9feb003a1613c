"""A declared void chamber that does not lie inside the design body (a chamber face glued
beside the body instead of cut out of it; a void face meeting the design at a corner only), and
a pressure inlet that borders no design element, are refused before any solve: one line naming
the region, exit code 2 (they ended in a failed linear solve and a traceback, exit code 1)."""
import pytest

from pacto_ng.params import InputError
from pacto_ng.template import TEMPLATE

from test_case_files import run_cli

pytestmark = pytest.mark.usefixtures("pacto_one_thread")

CUT = '''    chamber = occ.WorkPlane().Circle(0.35 * L, 0.5 * H, CHAMBER_R).Face()'''


def _case_file(folder, name, chamber):
    """The template's finger with its chamber replaced by ``chamber`` (netgen.occ code making
    a face ``chamber``), glued to the body without being cut out of it."""
    text = TEMPLATE.format(name=name, file=f"{name}.py")
    for old, new in ((CUT, f"    chamber = {chamber}"),
                     ("    design = body - chamber\n", "    design = body\n")):
        assert old in text, old
        text = text.replace(old, new)
    path = folder / f"{name}.py"
    path.write_text(text)
    return path


@pytest.mark.parametrize("name,chamber", [
    # beside the finger's tip, not touching it
    ("apart", "occ.WorkPlane().Circle(L + 0.01, 0.5 * H, CHAMBER_R).Face()"),
    # a square below the clamped edge, meeting the body at its corner (0, 0) only
    ("corner", "occ.WorkPlane().Rectangle(0.01, 0.01).Face().Move((-0.01, -0.01, 0))"),
])
def test_a_void_chamber_outside_the_body_is_refused_in_one_line(tmp_path, name, chamber):
    case = _case_file(tmp_path, name, chamber)
    out = tmp_path / "out"
    code, err = run_cli("run", case, "--iterations", "1", "--maxh", "0.003", "--out", out,
                        "--quiet")
    assert code == 2, err
    assert err.strip().count("\n") == 0, err
    assert err.strip() == (
        "pacto: error: void: face 'chamber' does not lie inside the design body (it shares no "
        "edge with face 'design'): cut the chamber out of the body and glue it back (see "
        "docs/tutorial.md)")


def test_a_chamber_cut_out_of_the_body_passes(tmp_path):
    """The template's own chamber (cut out and glued back) passes the check."""
    from pacto_ng.case import load_case_file, mesh_for
    from pacto_ng.setup_names import check_inlet_touches_design, check_setup_names

    path = tmp_path / "finger.py"
    path.write_text(TEMPLATE.format(name="finger", file="finger.py"))
    case = load_case_file(path)
    params = case.defaults.replace(maxh=0.003)
    setup = case.make_setup(params)
    mesh = mesh_for(case, params).mesh
    check_setup_names(mesh, setup)
    check_inlet_touches_design(mesh, setup.pressure.inlet, setup.void)


def _pad_mesh(inlet_end):
    """A 20 x 10 mm rectangle with a passive solid pad [0, 4] x [0, 2] mm in its lower left
    corner; the inlet on the bottom edge from x = 0 to ``inlet_end``."""
    from pacto_ng.mesh import Layout, Region, Segment, netgen_mesh

    return netgen_mesh(Layout(0.02, 0.01, segments=(Segment("inlet", (0, 0), (inlet_end, 0)),
                                                    Segment("fixed", (0, 0.01), (0, 0))),
                              regions=(Region("pad", "solid", 0, 0, 0.004, 0.002),)), 0.001)


def test_an_inlet_that_meets_the_design_at_a_vertex_only_is_refused():
    """An inlet along the pad's outer edge touches the design at the pad's corner (x = 4 mm)
    and borders only pad elements: it pressurises nothing."""
    from pacto_ng.setup_names import check_inlet_touches_design

    with pytest.raises(InputError) as err:
        check_inlet_touches_design(_pad_mesh(0.004), ("inlet",), ())
    assert str(err.value) == (
        "setup: pressure inlet 'inlet' touches no design domain (it borders pad); put it on "
        "an edge of the 'design' face or of a chamber inside it")
    # an inlet that runs on past the pad borders design elements
    check_inlet_touches_design(_pad_mesh(0.008), ("inlet",), ())
