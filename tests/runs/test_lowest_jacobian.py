"""summary.json's ``lowest_J`` / ``lowest_J_corners``: where det F of the analysed state is
lowest, checked against det F recomputed in numpy from design.vtu (Q1 shape functions on each
cell's corners and displacements, at the 2 x 2 Gauss points and at the corners)."""
import json

import numpy as np
import pytest

from pacto_ng.cli import main

pytestmark = pytest.mark.usefixtures("one_thread")

UNIT = ["--nelx", "12", "--nely", "8", "--set", "unit_elements=1", "--set", "plane=stress",
        "--set", "E1=1", "--set", "E0=1e-6", "--set", "thickness=0.5", "--set", "delta_s=1",
        "--set", "k_out=0.01", "--set", "filter_radius=2.5"]


def q1_detf(X, U, xi, eta):
    """det(I + ∇u) of the bilinear map of one quad (corners X, displacements U, 4 x 2, in
    the cell's cyclic order) at the reference point (xi, eta) of [0, 1]²."""
    dN = np.array([[-(1 - eta), -(1 - xi)], [1 - eta, -xi], [eta, xi], [-eta, 1 - xi]])
    dXdr = X.T @ dN  # 2 x 2
    dUdr = U.T @ dN
    G = dUdr @ np.linalg.inv(dXdr)
    return float(np.linalg.det(np.eye(2) + G))


def test_lowest_jacobian_matches_the_displacement_written(tmp_path):
    import meshio

    np.save(tmp_path / "rho.npy", np.full((8, 12), 0.5))
    out = tmp_path / "ev"
    assert main(["evaluate", "pa-inverter", *UNIT, "--model", "neohookean", "--load", "0.01",
                 "--density", str(tmp_path / "rho.npy"), "--out", str(out), "--quiet"]) == 0
    s = json.loads((out / "summary.json").read_text())
    m = meshio.read(out / "design.vtu")
    cells = np.concatenate([c.data for c in m.cells])
    u = np.asarray(m.point_data["u"])[:, :2]
    rho = np.asarray(m.point_data["rho_bar"]).reshape(len(m.points), -1)[:, 0]
    g = (0.5 - 0.5 / np.sqrt(3.0), 0.5 + 0.5 / np.sqrt(3.0))
    gauss = [(a, b) for a in g for b in g]
    corners = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
    at_gauss, at_corners = [], []
    for cell in cells:
        X, U = m.points[cell, :2], u[cell]
        at_gauss.append(min(q1_detf(X, U, *p) for p in gauss))
        at_corners.append(min(q1_detf(X, U, *p) for p in corners))
    for key, vals, kind in (("lowest_J", at_gauss, "quadrature point"),
                            ("lowest_J_corners", at_corners, "vertex")):
        low = s[key]
        el = int(np.argmin(vals))
        assert low["J"] == pytest.approx(vals[el], rel=1e-9)
        assert low["element"] == el
        assert low["rho_bar"] == pytest.approx(rho[cells[el][0]], rel=1e-12)
        assert low["point"] == kind
    assert s["lowest_J"]["J"] < 0.99  # the state is deformed: the check is not of F = I
