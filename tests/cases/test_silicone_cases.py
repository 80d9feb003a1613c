"""The silicone cases (gripper-silicone, pneunet-silicone): a material preset in real units.

Fast: a few iterations on a coarse mesh (the preset's stiffness and ν in summary.json, the
mixed formulation chosen, the objective going down) and the finite-difference check of each
case's whole chain, Wang (the default) under the follower and the fixed load and the Yeoh law
of the preset.  Slow (``-m slow``): the default run converges at its full load to a nearly
black-and-white design whose output moves the working way.
"""
from __future__ import annotations

import json

import meshio
import numpy as np
import pytest

from pacto_ng.cli import main

pytestmark = pytest.mark.usefixtures("pacto_one_thread")

CASES = ("gripper-silicone", "pneunet-silicone")
COARSE = ["--nelx", "40", "--nely", "20"]
#: Dragon Skin 30's published Yeoh C10 (Pa), transcribed from its source for this test
C10 = 153.6e3


@pytest.mark.parametrize("case", CASES)
def test_smoke_run(case, tmp_path):
    out = tmp_path / case
    assert main(["run", "--no-part", case, *COARSE, "--iterations", "5", "--out", str(out), "--quiet"]) == 0
    s = json.loads((out / "summary.json").read_text())
    p = s["parameters"]
    assert p["material"] == "dragonskin-30" and p["nu"] == 0.45
    assert p["E1"] == pytest.approx(2 * 2 * C10 * 1.45, rel=1e-12)
    assert s["formulation"] == "mixed" and s["model"] == "wang"
    assert s["objective_history"][-1] < s["objective_history"][0]


#: the Yeoh law everywhere (void included, E0 = 1e-6 E1 ≈ 0.9 Pa) under the follower load at
#: the cases' 10 kPa: the void's equilibrium beside the pressure gradients is nearly singular,
#: and the finite differences carry its noise (gripper-silicone: 3.6e-5) or Newton does not
#: find it (pneunet-silicone, also at 1e3 Pa: load factor 0.88; measured 2026-12-03).  With
#: E0 = 1e4 Pa the same checks pass at 10 kPa (8.8e-8 and 2.1e-9), and pneunet-silicone's at
#: 1e2 Pa with the case's E0 (2.0e-9).  Wang's void is linear: its check passes as it is.
@pytest.mark.parametrize("case", CASES)
@pytest.mark.parametrize("extra", [[], ["--set", "load_type=fixed"],
                                   ["--model", "yeoh", "--set", "E0=1e4"]],
                         ids=["wang-follower", "wang-fixed", "yeoh-follower"])
def test_check_gradients(case, extra, capsys):
    code = main(["check-gradients", case, *extra])
    out = capsys.readouterr().out
    assert code == 0, out[-2000:]
    assert "pass" in out and "d(objective)/dx" in out


@pytest.mark.slow
@pytest.mark.parametrize("case", CASES)
def test_default_run_converges_to_a_working_part(case, tmp_path):
    out = tmp_path / case
    assert main(["run", "--no-part", case, "--out", str(out), "--quiet"]) == 0
    s = json.loads((out / "summary.json").read_text())
    assert s["converged"] and s["load_factor_reached"] == 1.0
    assert s["output_displacement"] > 0.0
    rho = np.asarray(meshio.read(out / "design.vtu").point_data["rho_bar"])
    assert float(np.mean((rho > 0.1) & (rho < 0.9))) < 0.1


@pytest.mark.parametrize("extra, length", [([], 8e-4), (COARSE, 1e-3)],
                         ids=["default-mesh", "coarse"])
def test_gripper_silicone_s_spring_and_port_act_on_the_jaw_pad_s_edge(extra, length):
    """The output spring and port act on "output_edge", the jaw pad's right edge from its inner
    corner (40, 4) mm up 0.8 mm (the whole 0.5 mm element edges it reaches into on the coarse
    grid: 1 mm): every element edge of it borders the passive pad (so the part, which keeps
    the pad, has the same edge), and Δ is the edge's mean of -u_y; the layout refuses an edge
    longer than the pad's 1 mm."""
    from ngsolve import BND, Integrate

    from pacto_ng.case import build_problem, get_case
    from pacto_ng.geometries import pa_mechanism as geo
    from pacto_ng.threads import compute

    case = get_case("gripper-silicone")
    params = case.defaults.with_overrides(
        dict(zip([a.lstrip("-") for a in extra[::2]], extra[1::2])))
    setup = case.setup(params)
    assert setup.port.region == setup.springs[0].region == "output_edge"
    assert "output_edge" in setup.pressure.zero
    with compute():
        problem = build_problem(case, params)
        mesh = problem.mech.mesh
        edge = mesh.Boundaries("output_edge")
        assert Integrate(1.0, mesh, BND, definedon=edge) == pytest.approx(length, rel=1e-12)
        beside = {mesh[e].elements[0] for el in mesh.Elements(BND) if el.mat == "output_edge"
                  for e in el.edges}
        assert {mesh[el].mat for el in beside} == {"jaw_pad"}
        problem.evaluate(np.full(problem.field.n, 0.4))
        mean_uy = Integrate(problem.mech.u[1], mesh, BND, definedon=edge) / length
        assert float(problem.values["delta"]) == pytest.approx(-mean_uy, rel=1e-10)
    with pytest.raises(ValueError, match="^output_edge"):
        geo.layout(0.04, 0.02, gripper=True, output_edge=0.0011)
