"""summary.json reports every response of the final state, not only the objective's: the
compliance of an energy run, the output displacement of a case without a port (at its load, in
the load's direction), and null only where a response is undefined (a follower load has no
compliance).  The reference values are computed here, from the displacement field of the
written design.vtu or from an integral of this test's own."""
import json

import meshio
import numpy as np
import pytest

from pacto_ng.cli import main


def _summary(folder):
    return json.loads((folder / "summary.json").read_text())


def _displacement_at(folder, x, y):
    """u at the mesh node (x, y) of design.vtu (NGSolve writes each element's corners as
    points of their own: every copy of the node carries the same u of the H1 field)."""
    m = meshio.read(folder / "design.vtu")
    at = np.hypot(m.points[:, 0] - x, m.points[:, 1] - y) < 1e-9
    assert at.any(), f"no node at ({x}, {y})"
    u = np.asarray(m.point_data["u"])[at, :2]
    assert np.ptp(u, axis=0).max() <= 1e-12 * np.abs(u).max()
    return u[0]


def test_an_energy_run_reports_the_compliance_and_the_displacement_under_the_load(tmp_path):
    """MBB, objective strain energy: the unit load pulls the top-left corner (0, nely) down, so
    compliance f·u and the output displacement (at the load, along it) are both -u_y there."""
    out = tmp_path / "mbb"
    assert main(["run", "--no-part", "mbb", "--nelx", "12", "--nely", "4", "--iterations", "2", "--set",
                 "objective=energy", "--out", str(out), "--quiet"]) == 0
    s = _summary(out)
    assert s["objective_name"] == "se" and s["load"] == 1.0
    uy = _displacement_at(out, 0.0, 4.0)[1]
    assert uy < 0
    assert s["compliance"] == pytest.approx(-uy, rel=1e-10)
    assert s["output_displacement"] == pytest.approx(-uy, rel=1e-10)
    assert s["output_displacement_at"] == {
        "kind": "load", "terms": [{"region": "load", "direction": [0.0, -1.0], "weight": 1.0}]}


def test_the_cantilever_reports_the_mean_tip_deflection_under_its_load(tmp_path):
    """The cantilever's tip force is spread over mid-height ±2 element heights of the right
    edge (its case definition): Δ is the mean downward displacement over that patch.  Order 1
    on quads: u is linear between the nodes along the edge, so the trapezoidal mean of the
    nodes' values is exact."""
    out = tmp_path / "cant"
    assert main(["run", "--no-part", "cantilever", "--nelx", "24", "--nely", "8", "--iterations", "2",
                 "--set", "order=1", "--out", str(out), "--quiet"]) == 0
    s = _summary(out)
    h = 0.25 / 8
    ys = 0.125 + h * np.arange(-2, 3)
    uy = np.array([_displacement_at(out, 1.0, y)[1] for y in ys])
    weights = np.array([0.5, 1.0, 1.0, 1.0, 0.5]) / 4.0
    delta = -float(weights @ uy)
    assert delta > 0
    assert s["output_displacement"] == pytest.approx(delta, rel=1e-10)
    # the force spread uniformly over the patch does the work F · (mean u)
    assert s["compliance"] == pytest.approx(s["load"] * delta, rel=1e-10)
    assert s["output_displacement_at"]["kind"] == "load"


def test_a_pressure_case_reports_the_compliance_of_its_darcy_load(one_thread):
    """pa-inverter (mechanism objective, fixed Darcy load): the compliance f(p)·u =
    t ∫ -∇p·u dΩ, integrated here with a rule of its own."""
    from ngsolve import InnerProduct, Integrate, dx, grad

    from pacto_ng.case import build_problem, get_case
    from pacto_ng.outputs import compliance

    case = get_case("pa-inverter")
    params = case.parameters({"nelx": 12, "nely": 8})
    problem = build_problem(case, params)
    problem.evaluate(np.full(problem.field.n, 0.5), gradients=False)
    assert problem.objective != "compliance" and problem.setup.loads == ()
    u, p = problem.mech.gfu, problem.pressure_block.gfp
    ref = problem.params.thickness * Integrate(InnerProduct(-grad(p), u) * dx(bonus_intorder=4),
                                               problem.mesh)
    assert ref != 0
    assert compliance(problem) == pytest.approx(ref, rel=1e-10)


def test_a_follower_load_has_no_compliance(tmp_path):
    out = tmp_path / "paf"
    assert main(["run", "--no-part", "pa-inverter", "--nelx", "12", "--nely", "8", "--iterations", "1",
                 "--set", "load_type=follower", "--out", str(out), "--quiet"]) == 0
    s = _summary(out)
    assert s["compliance"] is None
    assert s["strain_energy"] > 0 and np.isfinite(s["output_displacement"])
    assert s["output_displacement_at"]["kind"] == "port"


def test_greyness_is_the_area_mean_of_4_rho_1_minus_rho_over_the_design_domain(one_thread):
    """Sigmund's measure of non-discreteness: 1 for ρ̄ = 0.5 everywhere (the mbb beam, no
    passive elements: x = 0.5 stays 0.5 through the filter), and on a random pa-inverter
    design the mean of 4 ρ̄ (1 - ρ̄) over the design elements (all of one area on a structured
    mesh; the passive block not counted)."""
    from pacto_ng.case import build_problem, get_case

    case = get_case("mbb")
    problem = build_problem(case, case.parameters({"nelx": 12, "nely": 4}))
    problem.evaluate(np.full(problem.field.n, 0.5), gradients=False)
    assert problem.greyness() == pytest.approx(1.0, abs=1e-12)
    case = get_case("pa-inverter")
    problem = build_problem(case, case.parameters({"nelx": 12, "nely": 8}))
    x = np.random.default_rng(3).uniform(0.0, 1.0, problem.field.n)
    problem.evaluate(x, gradients=False)
    rho = np.asarray(problem.values["rho_bar"])[problem.field.design]
    assert rho.size < problem.mesh.ne
    assert problem.greyness() == pytest.approx(float(np.mean(4 * rho * (1 - rho))), rel=1e-12)
