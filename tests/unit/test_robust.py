"""The robust formulation's parts (pacto_ng.robust): MMA's bound formulation of a worst case on
problems with a known minimax, the worst-case block, the dilated design's volume target and the
refused set-ups; and a short robust run through the driver."""
import dataclasses
import subprocess
import sys

import numpy as np
import pytest

from pacto_ng.builders import standard_chain
from pacto_ng.case import build_problem, get_case
from pacto_ng.core import check_gradient
from pacto_ng.optimize.mma import Optimizer
from pacto_ng.params import InputError
from pacto_ng.robust import VolumeTarget, WorstCase

pytestmark = pytest.mark.usefixtures("pacto_one_thread")


def _terms(x, offset):
    # f1 = (x0 - 0.2)² + (x1 - 0.3)², f2 = (x0 - 0.8)² + (x1 - 0.3)² (+ offset):
    # max(f1, f2) is least at x = (0.5, 0.3), where f1 = f2 = 0.09 (+ offset)
    t1, t2 = np.array([0.2, 0.3]), np.array([0.8, 0.3])
    F0 = np.array([((x - t1) ** 2).sum(), ((x - t2) ** 2).sum()]) + offset
    dF0 = np.array([2 * (x - t1), 2 * (x - t2)])
    f = np.array([x.sum() - 1.5])  # inactive at the minimax
    return F0, f, dF0, np.ones((1, 2))


def _minimax(method, offset, iterations=40):
    opt = Optimizer(2, 1, method=method, move=0.2, terms=2)
    x = np.array([0.1, 0.9])
    for it in range(1, iterations):
        F0, f, dF0, df = _terms(x, offset)
        x = opt.update(it, x, F0, dF0, f, df, evaluate=lambda z: _terms(z, offset)[:2])
    return x


@pytest.mark.parametrize("offset", [0.0, -5.0, 40.0])
def test_bound_formulation_gcmma_finds_the_minimax(offset):
    x = _minimax("gcmma", offset)
    assert np.allclose(x, [0.5, 0.3], atol=1e-4)
    assert max(_terms(x, offset)[0]) == pytest.approx(0.09 + offset, abs=1e-8)


def test_bound_formulation_mma_balances_the_terms(offset=-5.0):
    # the terms are balanced (x0 = 0.5) exactly; along x1, where both terms have one gradient,
    # MMA ends in its 2-cycle at the asymptotes' least distance 0.01 (the standard formulation
    # of min (x0-0.5)² + (x1-0.3)² ends in the same kind of cycle, 0.0074 from the optimum).
    # The cycle is reached by iteration 20 (measured: |x1 - 0.3| alternates 0.0063 / 0.0020
    # there, 0.0067 / 0.0016 at 39, the terms' excess 4.0e-5 / 4.5e-5); 25 iterations, not 40:
    # mmapy's subsolver takes longer at every step of the cycle (35 s for 40 on the loaded
    # 2-core machine, 13 s for 25)
    x = _minimax("mma", offset, iterations=25)
    assert x[0] == pytest.approx(0.5, abs=1e-6)
    assert abs(x[1] - 0.3) < 0.01
    assert max(_terms(x, offset)[0]) - (0.09 + offset) < 1e-4


def test_bound_formulation_respects_the_move_limit():
    opt = Optimizer(2, 1, method="mma", move=0.05, terms=2)
    x = np.array([0.1, 0.9])
    F0, f, dF0, df = _terms(x, 0.0)
    assert np.max(np.abs(opt.update(1, x, F0, dF0, f, df) - x)) <= 0.05 + 1e-12


def test_worst_case_block_value_and_gradient():
    blk = WorstCase(("a", "b", "c"))
    assert blk.forward(1.0, 3.0, 2.0) == 3.0
    assert blk.backward(2.0) == (0.0, 2.0, 0.0)
    # where the maximum is unique, the block's gradient is that of max(a·x) (FD check)
    A = np.array([[1.0, 2.0], [3.0, -1.0], [0.5, 0.5]])

    def fun(x):
        return blk.forward(*(A @ x))

    def grad(x):
        blk.forward(*(A @ x))
        return np.array(blk.backward(1.0)) @ A

    res = check_gradient(fun, grad, np.array([0.7, 0.2]), h=1e-6, directions=3)
    assert res.rel_error < 1e-8


class _Vol:
    volfrac = 0.2


def test_volume_target_follows_the_history_every_so_many_iterations():
    rows = [dict(iteration=i, vol_d=0.2 + 0.01 * i, vol_i=0.2) for i in range(45)]
    tgt = VolumeTarget(_Vol(), 0.2, 20)
    assert tgt.target(0, rows) == 0.2                 # before the first update: V*
    assert tgt.target(19, rows) == 0.2
    assert tgt.target(20, rows) == pytest.approx(0.2 * 0.39 / 0.2)  # row 19: V_d 0.39
    assert tgt.target(39, rows) == pytest.approx(0.39)
    assert tgt.target(44, rows) == pytest.approx(0.2 * 0.59 / 0.2)  # row 39: V_d 0.59
    tgt(44, rows)
    assert tgt.block.volfrac == pytest.approx(0.59)


def test_refused_set_ups():
    pa = get_case("pa-inverter")
    with pytest.raises(InputError, match="robust_deta"):
        build_problem(pa, pa.defaults.replace(robust=1, robust_deta=0.45, eta=0.6, nelx=12,
                                              nely=6))
    mm = get_case("mm-gripper")
    with pytest.raises(InputError, match="^robust: case 'mm-gripper' has two design fields"):
        build_problem(mm, mm.defaults.replace(robust=1, maxh=0.02))
    own = dataclasses.replace(pa, name="own-chain", chain=lambda b: standard_chain(b))
    with pytest.raises(InputError, match="^robust: case 'own-chain' builds its own chain"):
        build_problem(own, pa.defaults.replace(robust=2, nelx=12, nely=6))
    with pytest.raises(InputError, match="^robust: must be one of 0, 1, 2"):
        pa.defaults.replace(robust=3)


def test_several_ports_each_reported_in_every_realisation():
    """The jaw-gripper's two jaws: each jaw's own d·u is a reported value of the standard
    chain, of the blueprint and of the eroded and dilated designs, and they add up to Δ."""
    jaw = get_case("jaw-gripper")
    problem = build_problem(jaw, jaw.defaults.replace(robust=1, maxh=0.01))
    for tag in ("", "_e", "_d"):
        assert {f"delta_top_jaw{tag}", f"delta_bottom_jaw{tag}"} <= set(problem.reports)
    vals = problem.chain.forward(x=np.full(problem.n_design, 0.5))
    for tag in ("", "_e", "_d"):
        assert vals[f"delta{tag}"] == pytest.approx(
            vals[f"delta_top_jaw{tag}"] + vals[f"delta_bottom_jaw{tag}"], rel=1e-12)


def test_cli_refuses_a_bad_robust_setting_in_one_line():
    out = subprocess.run([sys.executable, "-m", "pacto_ng.cli", "run", "pa-inverter", "--set",
                          "robust_deta=0.7", "--iterations", "1", "--out", "/nonexistent/x"],
                         capture_output=True, text=True)
    assert out.returncode == 2
    assert out.stderr.strip().count("\n") == 0 and "robust_deta" in out.stderr


def test_a_short_robust_run_reports_the_worst_case_and_updates_the_target(tmp_path):
    from pacto_ng.runner import optimise_case

    pa = get_case("pa-inverter")
    params = pa.defaults.replace(robust=1, robust_every=2, nelx=12, nely=6, iterations=5,
                                 penal_start=3.0, beta=4.0, beta_max=4.0)
    run = optimise_case(pa, params, tmp_path / "r", quiet=True)
    assert run.exit_code == 0
    rows = run.history
    assert len(rows) == 5
    for r in rows:
        assert r["objective"] == max(r["objective_e"], r["objective_i"], r["objective_d"])
        assert r["vol_d"] > r["volume"] and r["vol_i"] == pytest.approx(r["volume"], rel=1e-12)
    # newton counts the three realisations' analyses (linear: one Newton step each)
    assert all(r["newton"] == 3 and r["load_steps"] == 3 for r in rows)
    # the dilated design's volume target at the last iteration (4): V* V_d/V_i of iteration 3
    vol_d = next(b for b in run.problem.chain.blocks if b.output == "volume_d")
    assert vol_d.volfrac == pytest.approx(0.2 * rows[3]["vol_d"] / rows[3]["vol_i"], rel=1e-12)


def test_warm_states_of_every_realisation_are_saved_and_restored():
    """``Problem.warm`` holds each mechanics block's equilibrium (the driver restores it before
    analysing a cut design step): after another design's analysis, ``set_warm`` puts back the
    first design's displacements and Newton records in the blueprint and the eroded
    realisation, and re-analysing the first design from there takes no Newton step."""
    pa = get_case("pa-inverter")
    problem = build_problem(pa, pa.defaults.replace(robust=2, model="wang", nelx=12, nely=6,
                                                    load=3e5))
    mechs = [problem.mech] + list(problem.extra_mechanics)
    assert len(mechs) == 2
    rng = np.random.default_rng(3)
    x1 = np.clip(0.5 + 0.2 * rng.standard_normal(problem.n_design), 0, 1)
    x2 = np.clip(x1 + 0.2 * rng.standard_normal(problem.n_design), 0, 1)
    problem.evaluate(x1, gradients=False)
    saved = problem.warm
    u1 = [m.state.u for m in mechs]
    assert all(m.result.converged and m.result.iterations > 1 for m in mechs)
    problem.evaluate(x2, gradients=False)
    assert all(np.max(np.abs(m.state.u - u)) > 1e-3 * np.max(np.abs(u))
               for m, u in zip(mechs, u1))
    problem.set_warm(saved)
    for m, u, (_, res) in zip(mechs, u1, saved):
        np.testing.assert_array_equal(m.state.u, u)
        assert m.result is res
    problem.evaluate(x1, gradients=False)
    assert all(m.result.converged and m.result.iterations == 0 for m in mechs)
