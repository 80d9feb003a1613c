"""--model auto and load_ramp=-1: chosen from the material's strain in one linear analysis of
the initial design, said why, and recorded in summary.json."""
import json
import math
from types import SimpleNamespace

import pytest

from pacto_ng.auto import choose_ramp, material_strain
from pacto_ng.cli import main
from pacto_ng.optimize.schedules import Schedule

pytestmark = pytest.mark.usefixtures("pacto_one_thread")


def _choice(tmp_path, load, model="auto", iterations=1):
    out = tmp_path / f"{model}-{load}"
    assert main(["run", "--no-part", "cantilever", "--model", model, "--load", str(load), "--maxh", "0.03",
                 "--iterations", str(iterations), "--out", str(out), "--quiet"]) == 0
    s = json.loads((out / "summary.json").read_text())
    return s


def test_auto_picks_by_strain(tmp_path):
    small = _choice(tmp_path, 1e3)
    big = _choice(tmp_path, 1e4, iterations=24)  # room for its ramp
    for s in (small, big):
        assert s["model"] == s["model_choice"]["chosen"]
    small, big_ramp, big = small["model_choice"], big["load_ramp_choice"], big["model_choice"]
    assert small["chosen"] == "linear" and small["strain_p99"] < 0.01
    assert big["chosen"] == "wang" and big["strain_p99"] >= 0.01
    # the measurement is the linear analysis': ten times the load, (nearly) ten times the strain
    # (the quadratic part of the Green-Lagrange strain adds ~1 % at 2 % strain)
    assert abs(big["strain_p99"] / small["strain_p99"] - 10.0) / 10.0 < 0.03
    assert "99th percentile" in big["reason"]
    # the nonlinear run's ramp: one iteration per 1 % of that strain, recorded resolved in
    # params.json (a resume continues the same ramp); iteration 0 runs at 1/n of the load
    n = big_ramp["chosen"]
    assert n == math.ceil(big["strain_p99"] / 0.01) and n > 1
    out = tmp_path / "auto-10000.0"
    assert json.loads((out / "params.json").read_text())["params"]["load_ramp"] == n
    rows = [r.split(",") for r in (out / "history.csv").read_text().splitlines()]
    assert abs(float(dict(zip(rows[0], rows[1]))["load"]) - 1.0 / n) < 1e-12


def test_auto_on_pa_inverter(tmp_path):
    """Linear at 1e5 Pa, nonlinear at 1e7 Pa (coarse mesh; the choice is made from the first
    linear analysis and recorded before any optimisation)."""
    chosen = {}
    for load in ("1e5", "1e7"):
        out = tmp_path / load
        code = main(["run", "--no-part", "pa-inverter", "--model", "auto", "--load", load, "--maxh", "0.01",
                     "--iterations", "0", "--out", str(out), "--quiet"])
        assert code in (0, 1)  # 1: the final nonlinear analysis may stop cleanly at 1e7 Pa
        chosen[load] = json.loads((out / "params.json").read_text())["model_choice"]["chosen"]
    assert chosen == {"1e5": "linear", "1e7": "wang"}


def test_choose_ramp():
    pa = Schedule(penal=3, penal_start=2, penal_step=0.04, beta_start=1, beta_max=32,
                  beta_every=15)
    assert pa.final_at() == 25 + 5 * 15
    assert pa.values(pa.final_at())[:2] == (3, 32) and pa.values(pa.final_at() - 1)[1] == 16
    assert choose_ramp(0.009, pa, 160)[0] == 0  # small strains: full load at once
    assert choose_ramp(0.3, pa, 160)[0] == 30
    assert choose_ramp(4.2, pa, 160)[0] == 100  # ends with the continuation
    assert choose_ramp(4.2, Schedule(), 160)[0] == 80  # none: half the iterations
    assert choose_ramp(4.2, pa, 40)[0] == 39  # a short run ends at its full load
    assert choose_ramp(4.2, pa, 2)[0] == 0 and choose_ramp(4.2, pa, 1)[0] == 0  # no room


@pytest.mark.parametrize("rho_right, expected", [(1e-3, "left"), (0.1, "right")])
def test_material_strain_weights_by_density(rho_right, expected):
    """Left half strained 1 % (ρ̄ = 1), right half 100 % (ρ̄ = rho_right): the strain that 99 % of
    the material stays below is the left half's while the right holds under 1 % of the
    material (0.0005 / 0.5005), the right half's when it holds more (0.05 / 0.55)."""
    from ngsolve import CF, IfPos, L2, GridFunction, VectorH1, dx, x
    from ngsolve.meshes import MakeStructured2DMesh

    from pacto_ng.physics.quadrature import integration_rules

    mesh = MakeStructured2DMesh(quads=False, nx=8, ny=4)
    fes = VectorH1(mesh, order=1)
    gfu = GridFunction(fes)
    e1, e2 = 0.01, 1.0
    gfu.Set(CF((IfPos(x - 0.5, 0.5 * e1 + e2 * (x - 0.5), e1 * x), 0)))
    rho = GridFunction(L2(mesh, order=0))
    rho.Set(IfPos(x - 0.5, rho_right, 1.0))
    rules = integration_rules(2)
    mech = SimpleNamespace(u=gfu, mesh=mesh, rules=rules, DX=dx(intrules=rules),
                           fields=[SimpleNamespace(gf=rho)])
    s, largest = material_strain(mech)
    gl = {"left": e1 + e1 ** 2 / 2, "right": e2 + e2 ** 2 / 2}  # E_xx = e + e²/2
    assert abs(s - gl[expected]) < 1e-12
    assert abs(largest - gl["left"]) < 1e-12  # the largest where ρ̄ >= 0.5
