"""Every run ends with its part (pacto_ng.post.part_stage): made, checked for a seal, analysed
at the run's load, reported in summary.json and in the run's last line."""
import json

import numpy as np
import pytest
from netgen.occ import OCCGeometry, Rectangle
from ngsolve import Mesh

from pacto_ng.case import build_problem, get_case
from pacto_ng.cli import main
from pacto_ng.params import Parameters
from pacto_ng.physics.loads import Port
from pacto_ng.physics.mechanics import Supports
from pacto_ng.post import part_stage
from pacto_ng.post.part_analysis import PartAnalysis
from pacto_ng.post.part_stage import beyond_linear, finish_run
from pacto_ng.threads import compute

#: the PneuNet member (chamber x 0.02-0.08, y 0.01-0.02 in a 0.1 x 0.05 domain), coarse
COARSE = dict(maxh=0.004)
#: a void channel from the chamber's roof to the top edge
CHANNEL = (0.042, 0.058, 0.02, 0.05)


def _design(problem, channel: bool) -> np.ndarray:
    """All solid, or with a void channel through the roof."""
    from ngsolve import VOL

    mesh = problem.mesh
    c = np.array([np.mean([mesh[v].point for v in el.vertices], axis=0)
                  for el in mesh.Elements(VOL)])
    x = np.ones(len(c))
    if channel:
        x0, x1, y0, y1 = CHANNEL
        x[(c[:, 0] > x0) & (c[:, 0] < x1) & (c[:, 1] > y0 - 0.002) & (c[:, 1] < y1)] = 0.0
    return x[problem.field.design]  # the design variables: the chamber is passive void


@pytest.fixture(scope="module")
def pneunet():
    case = get_case("pneunet")
    params = case.resolve(case.defaults.replace(**COARSE))
    with compute():
        problem = build_problem(case, params)
        problem.apply_schedule(3.0, 32.0, 1.0)
    return problem


def _finish(problem, x, tmp_path, capsys):
    with compute():
        problem.evaluate(x, gradients=False)
    summary = {"output_displacement": float(problem.values["delta"]),
               "load_reached": problem.params.load, "load_unit": "Pa"}
    out = finish_run(tmp_path, problem, summary, quiet=False)
    return out, capsys.readouterr().out


def test_a_solid_member_is_sealed_and_its_part_is_analysed(pneunet, tmp_path, capsys):
    summary, line = _finish(pneunet, _design(pneunet, False), tmp_path, capsys)
    part = summary["part"]
    assert part["made"] and part["sealed"] is True and summary["sealed"] is True
    assert [c["name"] for c in part["seal"]["chambers"]] == ["chamber"]
    assert part["analysed"] and part["converged"] and part["kind"] == "fixed"
    # all solid: the part is the whole member, whose area is the domain's less the chamber's
    assert part["measure"] == pytest.approx(0.1 * 0.05 - 0.06 * 0.01, rel=1e-3)
    # the design's Δ the part is compared with: at the part's order 2 on the run's mesh, as
    # a problem of that order built and meshed on its own gives it
    case, params = pneunet.case, pneunet.params
    with compute():
        second = build_problem(case, params.replace(order=2))
        second.apply_schedule(*pneunet.schedule_now())
        second.evaluate(_design(pneunet, False), gradients=False)
    assert (part["order"], part["design_order"], part["run_order"]) == (2, 2, 1)
    assert part["output_displacement_design"] == pytest.approx(second.values["delta"],
                                                               rel=1e-9)
    assert part["output_displacement_run"] == pytest.approx(pneunet.values["delta"], rel=1e-12)
    d, e, r = (part[k] for k in ("output_displacement", "output_displacement_design",
                                 "output_displacement_run"))
    assert part["gap"] == pytest.approx((d - e) / e) and part["gap_to_run"] == pytest.approx(
        (d - r) / r)
    assert (tmp_path / "part.stl").stat().st_size > 84 and (tmp_path / "part.png").exists()
    assert json.loads((tmp_path / "summary.json").read_text())["part"]["sealed"] is True
    assert "sealed" in line and "NOT SEALED" not in line


def test_an_open_chamber_is_reported_in_the_summary_and_the_last_line(pneunet, tmp_path,
                                                                      capsys):
    summary, line = _finish(pneunet, _design(pneunet, True), tmp_path, capsys)
    part = summary["part"]
    assert part["sealed"] is False and summary["sealed"] is False
    (chamber,) = part["seal"]["chambers"]
    assert chamber["name"] == "chamber" and chamber["boundary"] == "zero_pressure"
    x0, x1, _, y1 = CHANNEL
    assert x0 - 0.004 <= chamber["opening"][0] <= x1 + 0.004
    assert chamber["opening"][1] == pytest.approx(y1)
    assert "NOT SEALED" in line and "will not hold pressure" in line


def _run_from(tmp_path, *, channel: bool, extra=()):
    """``pacto run pneunet`` for one iteration from the member with (or without) an open
    channel (init_design): ``(run folder, exit code)``."""
    case = get_case("pneunet")
    with compute():
        problem = build_problem(case, case.resolve(case.defaults.replace(**COARSE)))
    start = tmp_path / "start"
    start.mkdir()
    np.savez(start / "checkpoint.npz", x=_design(problem, channel))
    out = tmp_path / "run"
    code = main(["run", "pneunet", "--maxh", "0.004", "--iterations", "1", "--quiet", *extra,
                 "--set", f"init_design={start}", "--set", "beta=32", "--set", "penal_start=3",
                 "--out", str(out)])
    return out, code


def test_a_run_s_last_line_says_its_chamber_is_open(tmp_path, capsys):
    """``pacto run`` from a design with an open chamber (init_design), one iteration: the
    optimiser's move limit cannot close the channel, and the run says so."""
    out, code = _run_from(tmp_path, channel=True)
    printed = capsys.readouterr().out
    assert code == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["sealed"] is False
    assert "NOT SEALED" in printed.strip().splitlines()[-1]
    # the export of that run's part says it too (on stderr, even with --quiet); a sealed
    # part's export says nothing of the kind
    assert main(["export", str(out), "--format", "stl", "--quiet"]) == 0
    err = capsys.readouterr().err
    assert "NOT SEALED" in err and "chamber 'chamber'" in err and "zero_pressure" in err


def test_a_sealed_part_s_export_warns_of_nothing(tmp_path, capsys):
    """The same run from the closed member (no channel): its export says nothing of a seal."""
    out, code = _run_from(tmp_path, channel=False, extra=("--no-part",))
    assert code == 0
    capsys.readouterr()
    assert main(["export", str(out), "--format", "stl", "--quiet"]) == 0
    assert "NOT SEALED" not in capsys.readouterr().err


def test_a_linear_part_that_moves_far_is_told_its_figures_do_not_hold():
    """A part 2 m x 1 m (size 2 m): a linear analysis that moves it 0.1 m (5 %) is kept quiet,
    one that moves it 0.3 m (15 %, above LINEAR_LIMIT = 10 %) is told to use a large-strain
    model."""
    mesh = Mesh(OCCGeometry(Rectangle(2.0, 1.0).Face(), dim=2).GenerateMesh(maxh=0.5))
    assert beyond_linear(mesh, 0.1) == []
    (line,) = beyond_linear(mesh, 0.3)
    assert "15% of its size (2 m)" in line and "--model neohookean" in line


@pytest.mark.parametrize("robust", [1, 2])
def test_a_robust_design_at_the_part_s_order_is_its_intermediate_design(robust):
    """The design's Δ at the part's order of a robust run (one analysis of the standard chain)
    is the Δ of the robust chain itself built at that order (its intermediate design's)."""
    from pacto_ng.post.runs import at_order, design_delta

    case = get_case("pa-inverter")
    params = case.resolve(case.defaults.replace(nelx=24, nely=12, robust=robust))
    with compute():
        run = build_problem(case, params)
        x = np.random.default_rng(0).uniform(0.2, 0.9, run.field.n)
        run.apply_schedule(3.0, 8.0, 1.0)
        run.chain.forward(x=x)
        second = build_problem(case, params.replace(order=2))
        second.apply_schedule(3.0, 8.0, 1.0)
        second.chain.forward(x=x)
        twin = at_order(run, 2)
    assert second.objective == "worst_case" and twin.objective == "objective"
    assert design_delta(twin) == pytest.approx(second.values["delta"], rel=1e-10)
    assert abs(design_delta(twin) / run.values["delta"] - 1) > 1e-3  # order 2 is not order 1


@pytest.mark.parametrize("robust", [0, 1])
def test_a_part_off_its_design_is_told_what_to_change(robust):
    """The last line of a part 50 % off its design: the robust formulation, unless the run
    had it already (then where the gap comes from)."""
    from pacto_ng.post.part_stage import last_line

    part = {"made": True, "sealed": True, "analysed": True, "converged": True, "kind": "fixed",
            "load": 1e5, "output_displacement": 1.5e-3, "output_displacement_design": 1e-3,
            "gap": 0.5, "order": 2, "run_order": 2, "warnings": []}
    line = last_line({"part": part, "load_unit": "Pa", "parameters": {"robust": robust}},
                     "RUN")
    assert "(+50.0 %) — not as designed" in line
    assert ("--set robust=1" in line) is (robust == 0)
    assert ("'pacto analyse RUN'" in line) is (robust == 1)


def test_a_part_that_is_not_analysed_says_so():
    """A case without pressure or port (the MBB beam): its part is made, and the last line
    says why it is not analysed instead of nothing."""
    from pacto_ng.post.part_stage import last_line

    why = "the part is analysed for pressure cases with an output port"
    line = last_line({"part": {"made": True, "analysed": False, "why_not_analysed": why,
                               "sealed": None}}, "RUN")
    assert line == f"part: made, not analysed ({why}) — RUN/part.stl"


def test_a_long_load_ramp_says_each_step_it_reaches(monkeypatch):
    """The part's analysis calls its mechanics' ``on_step`` at every equilibrium of Newton's
    load ramp from rest; the part stage's lines name the steps below the load once the
    analysis has taken PROGRESS_AFTER seconds (0 here), none without a printer."""
    shape = Rectangle(2.0, 0.5).Face()
    for e in shape.edges:
        c = e.center
        e.name = ("left" if abs(c.x) < 1e-9 else "right" if abs(c.x - 2) < 1e-9 else
                  "pressure" if abs(c.y) < 1e-9 else "top")
    mesh = Mesh(OCCGeometry(shape, dim=2).GenerateMesh(maxh=0.25))
    params = Parameters(model="neohookean", E1=1.0, E0=1e-3, E2=1.0, nu=0.3, plane="strain",
                        thickness=1.0, order=1)
    ana = PartAnalysis(mesh, "fixed", params=params, supports=Supports(clamp=("left",)),
                       ports=Port("right", (0.0, 1.0)))
    reached = []
    ana.mech.on_step = lambda load, _state: reached.append(load)
    with compute(1):
        assert ana.solve(0.05).converged
    assert len(reached) >= 2 and reached[-1] == pytest.approx(0.05) and reached[0] < 0.05
    monkeypatch.setattr(part_stage, "PROGRESS_AFTER", 0.0)
    lines = []
    step = part_stage.load_ramp_progress(lines.append, 1e4, "Pa")
    for load in (2500.0, 1e4):
        step(load, None)
    assert lines == ["reached 2500 of 1e+04 Pa on the load ramp"]
    assert part_stage.load_ramp_progress(None, 1e4, "Pa") is None


def test_a_part_without_an_equilibrium_at_the_load_says_how_far_it_got():
    """The last line of a sealed part whose analysis stopped short of the run's load names
    the load its equilibria reached (an earlier summary without it, only the failure)."""
    part = {"made": True, "sealed": True, "analysed": True, "converged": False,
            "kind": "follower", "load": 1e4, "load_reached": 9873.0}
    line = part_stage.last_line({"part": part, "load_unit": "Pa"}, "RUN")
    assert ("its follower analysis at 1e+04 Pa did not converge (equilibria up to 9873 Pa)"
            in line)
    del part["load_reached"]
    assert "did not converge —" in part_stage.last_line({"part": part, "load_unit": "Pa"},
                                                         "RUN")


def test_a_distributed_run_s_part_that_cannot_be_made_on_one_process_is_said_in_one_line(
        tmp_path, capsys):
    """A distributed run's part is made by its rank 0 from the final design analysed on the
    serial mesh; where that cannot be made (here: no finished run in the folder, as a serial
    problem too large for the machine is refused), one warning line names the reason and
    ``pacto analyse DIR``, no part is made, and the run's exit code stands."""
    from types import SimpleNamespace

    from pacto_ng.commands import _part_problem, _with_part

    done = SimpleNamespace(problem=SimpleNamespace(numbering=object()), exit_code=0,
                           summary={})
    assert _part_problem(done, tmp_path, "run") is None
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("pacto: warning: the part was not made: run: ")
    assert f"'pacto analyse {tmp_path}' makes it" in err[0]
    args = SimpleNamespace(no_part=False, command="run", quiet=True)
    assert _with_part(done, tmp_path, args) == 0
    assert not (tmp_path / "part.stl").exists()
