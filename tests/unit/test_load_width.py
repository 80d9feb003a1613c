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
    code = main(["run", "cantilever", "--set", "load_width=-1", "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert code != 0 and "load_width" in err and "Traceback" not in err
