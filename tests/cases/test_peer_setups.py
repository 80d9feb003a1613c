"""The published MATLAB codes' set-ups, node for node: ``pacto evaluate sorotop`` and
``pacto evaluate topress`` on a non-uniform density field against an independent numpy
transcription of each code's analysis (tests/kumar_reference.py), to 1e-10."""
import json

import numpy as np

import kumar_reference as ref
from pacto_ng import main

NELX, NELY = 60, 40


def density(nelx=NELX, nely=NELY):
    """A smooth non-uniform ρ̄ in [0.02, 0.98] as a nely x nelx grid, row 0 the top row (the
    density-file format of ``pacto evaluate``); it crosses the Darcy threshold ηf = 0.2 so
    that the pressure front runs through the domain."""
    x = (np.arange(nelx) + 0.5) / nelx
    y = 1 - (np.arange(nely) + 0.5) / nely  # row 0 at the top
    X, Y = np.meshgrid(x, y)
    return np.clip(0.45 + 0.4 * np.sin(3 * np.pi * X) * np.cos(2 * np.pi * Y)
                   + 0.1 * np.cos(7 * X + 3 * Y), 0.02, 0.98)


def evaluate(case, grid, tmp_path, *extra):
    f = tmp_path / f"{case}.npy"
    np.save(f, grid)
    out = tmp_path / f"ev-{case}"
    nely, nelx = grid.shape
    assert main(["evaluate", case, "--nelx", str(nelx), "--nely", str(nely), "--density",
                 str(f), "--out", str(out), *extra]) == 0
    return json.loads((out / "summary.json").read_text())


def rel(a, b):
    return abs(a - b) / abs(b)


def test_sorotop_matches_the_codes_analysis(tmp_path, one_thread):
    g = density()
    s = evaluate("sorotop", g, tmp_path)
    r = ref.sorotop(g.ravel("F"), NELX, NELY)
    # the code's objective is u_x of the output node (minimised); ours reports Δ = -u_x
    assert rel(s["output_displacement"], -r["u_out"]) < 1e-10
    # the structure's strain energy ½UᵀK₀U; the code's SE ½UᵀKU counts the output spring
    # too: UᵀKU is our compliance f·u (springs included)
    assert rel(s["strain_energy"], r["se"]) < 1e-10
    assert rel(s["compliance"], r["uku"]) < 1e-10


def test_sorotop_other_mesh_clamps_floor_nely_over_20_nodes(tmp_path, one_thread):
    # nely = 60: three clamped top nodes (x = 0, 1, 2), a 3 x 4 passive block
    g = density(80, 60)
    s = evaluate("sorotop", g, tmp_path)
    r = ref.sorotop(g.ravel("F"), 80, 60)
    assert rel(s["output_displacement"], -r["u_out"]) < 1e-10
    assert rel(s["strain_energy"], r["se"]) < 1e-10


def test_topress_matches_the_codes_analysis(tmp_path, one_thread):
    g = density()
    s = evaluate("topress", g, tmp_path)
    r = ref.topress(g.ravel("F"), NELX, NELY)
    assert rel(s["compliance"], r["compliance"]) < 1e-10
    assert rel(s["objective"], r["compliance"]) < 1e-10


def test_the_old_unit_element_pa_inverter_differs(tmp_path, one_thread):
    """What the node-for-node case fixes: the unit-element pa-inverter (with SoRoTop's
    parameters) clamps the top edge up to x = nelx/20 (4 nodes at 60 x 40, the code 2) and
    gives the top-left corner p = 0 (the code P_in)."""
    g = density()
    s = evaluate("sorotop", g, tmp_path)
    sets = {"unit_elements": 1, "plane": "stress", "E1": 1, "E0": 1e-6, "nu": 0.3,
            "thickness": 1, "load": 1, "delta_s": 2, "k_out": 0.1, "eta_k": 0.2, "eta_h": 0.2,
            "filter": "cone", "filter_radius": 2.4}
    extra = [a for k, v in sets.items() for a in ("--set", f"{k}={v}")]
    p = evaluate("pa-inverter", g, tmp_path, *extra)
    d_delta = rel(p["output_displacement"], s["output_displacement"])
    d_se = rel(p["strain_energy"], s["strain_energy"])
    print(f"pa-inverter against sorotop: Δ {d_delta:.3%}, SE {d_se:.3%}")
    assert d_delta > 1e-3 and d_se > 1e-3
