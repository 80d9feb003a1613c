"""The smallest member width (pacto_ng.member_width) of designs whose widths are known: bars
cut from a piecewise linear nodal field, whose 0.5 iso-lines lie on grid lines."""
import numpy as np
import pytest

from pacto_ng.member_width import member_width


def _grid(nx=200, ny=100, size=(0.1, 0.05)):
    xs, ys = np.linspace(0, size[0], nx + 1), np.linspace(0, size[1], ny + 1)
    X, Y = np.meshgrid(xs, ys)
    pts = np.column_stack([X.ravel(), Y.ravel()])
    idx = np.arange(pts.shape[0]).reshape(ny + 1, nx + 1)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, 1:].ravel(), idx[1:, :-1].ravel()
    tris = np.vstack([np.column_stack([a, b, c]), np.column_stack([a, c, d])])
    return pts, tris


def _bar(coord, centre, half_width):
    # 1 at the centre line, 0.5 at distance half_width: the part is |coord - centre| <= half_width
    return 1.0 - 0.5 * np.abs(coord - centre) / half_width


def test_two_bars_give_the_thinner_width():
    # two bars across the domain (their ends on its edges, which count as solid), 3 and 6 mm
    pts, tris = _grid()
    rho = np.maximum(_bar(pts[:, 1], 0.015, 0.0015), _bar(pts[:, 1], 0.035, 0.003))
    w = member_width(pts, tris, rho, pixel=1e-4)
    assert w["min"] == pytest.approx(0.003, abs=2e-4)
    assert w["q05"] == pytest.approx(0.003, abs=2e-4)


def test_one_bar_gives_its_width():
    pts, tris = _grid()
    w = member_width(pts, tris, _bar(pts[:, 0], 0.06, 0.003), pixel=1e-4)
    assert w["min"] == pytest.approx(0.006, abs=2e-4)   # the vertical bar: 6 mm


def test_no_solid_is_an_error():
    pts, tris = _grid(20, 10)
    with pytest.raises(ValueError, match="no solid"):
        member_width(pts, tris, np.zeros(len(pts)))
