"""``load_width``: a spread force load of a fixed width, independent of the mesh size."""
import pytest

from pacto_ng.case import get_case
from pacto_ng.cli import main


def _segment(layout, name):
    return next(s for s in layout.segments if s.name == name)


@pytest.mark.parametrize("case, segment, default_width", [
    ("cantilever", "load", lambda p: 4.0 * p.maxh),      # ± 2 element sizes
    ("inverter", "input", lambda p: 2.0 * p.maxh),       # two element heights
])
def test_load_width_fixes_the_loaded_segment(case, segment, default_width):
    c = get_case(case)
    for maxh in (c.defaults.maxh, 0.5 * c.defaults.maxh):
        p = c.defaults.with_overrides({"maxh": str(maxh)})
        s = _segment(c.geometry(p), segment)
        length = abs(s.end[1] - s.start[1])
        assert length == pytest.approx(default_width(p), rel=1e-12)
        fixed = 3.0 * c.defaults.maxh
        p = c.defaults.with_overrides({"maxh": str(maxh), "load_width": str(fixed)})
        s = _segment(c.geometry(p), segment)
        assert abs(s.end[1] - s.start[1]) == pytest.approx(fixed, rel=1e-12)


def test_negative_load_width_is_a_one_line_error(tmp_path, capsys):
    code = main(["run", "--no-part", "cantilever", "--set", "load_width=-1", "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert code != 0 and "load_width" in err and "Traceback" not in err


def test_a_segment_between_grid_nodes_is_said_with_the_length_it_covers(capsys):
    """On 50 x 12 quads of the 1 x 0.25 m cantilever (element height 0.25/12 m), a load patch
    of 0.036 m centred at mid-height covers the two element edges whose midpoints it holds:
    2 x 0.25/12 = 0.04167 m, and stderr says so."""
    from pacto_ng.case import get_case, mesh_for

    case = get_case("cantilever")
    mesh_for(case, case.resolve(case.defaults.replace(nelx=50, nely=12, load_width=0.036)))
    err = capsys.readouterr().err
    assert f"'load' 0.036 -> {2 * 0.25 / 12:.4g}" in err
    mesh_for(case, case.resolve(case.defaults.replace(nelx=50, nely=12,
                                                      load_width=2 * 0.25 / 12)))
    assert "load" not in capsys.readouterr().err  # on the nodes: nothing to say


def test_a_segment_ending_at_an_edge_s_midpoint_is_said_with_the_length_the_mesh_names(capsys):
    """A segment whose end lies on an element edge's midpoint (to round-off) takes that edge,
    and the line says the length the mesh names: on 100 x 50 quads of 0.04 x 0.02 m (edges of
    0.4 mm), the right edge's segment from 4 to 5 mm ends on the midpoint of the edge from 4.8
    to 5.2 mm (computed as 0.005000000000000001), so it covers 1.2 mm."""
    from ngsolve import BND, Integrate

    from pacto_ng.mesh import Layout, Segment, structured_mesh

    layout = Layout(0.04, 0.02, segments=(Segment("edge", (0.04, 0.004), (0.04, 0.005)),))
    mesh = structured_mesh(layout, 100, 50)
    named = Integrate(1.0, mesh, BND, definedon=mesh.Boundaries("edge"))
    assert named == pytest.approx(1.2e-3, rel=1e-9)
    assert "'edge' 0.001 -> 0.0012" in capsys.readouterr().err
