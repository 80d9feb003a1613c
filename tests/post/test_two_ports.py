"""pacto analyse / export / compare on a run with two output ports (jaw-gripper: Δ = d_top·u(top
jaw) + d_bottom·u(bottom jaw), each jaw against its own spring k_out).

A short run on a coarse mesh (20 iterations, about 10 s), analysed at two small pressures.  The
checks recompute what they can on their own: Δ and every port's value from the displacement
field written to remeshed.vtu at the jaw tips (their place taken from the case's geometry), and
the expected Δ from the run's summary.json (a linear run: Δ scales with the pressure).
"""
import json

import numpy as np
import pytest

from pacto_ng.cli import main

pytestmark = pytest.mark.usefixtures("pacto_one_thread")

PRESSURES = [1e2, 1e3]
PORTS = ("top_jaw", "bottom_jaw")


@pytest.fixture(scope="module")
def jaw_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("two_ports") / "jaw"
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("PACTO_THREADS", "1")
        # no penalty continuation, a large move limit and a filter of two elements: a design
        # that reaches both jaws from the mounts within 20 iterations
        assert main(["run", "jaw-gripper", "--maxh", "0.008", "--iterations", "20",
                     "--set", "penal_start=0", "--set", "move=0.2", "--set", "filter_radius=0.016",
                     "--out", str(out), "--quiet"]) == 0
        assert main(["analyse", str(out), "--pressures", ",".join(map(str, PRESSURES)),
                     "--quiet"]) == 0
    return out


@pytest.fixture(scope="module")
def analysis(jaw_run):
    return json.loads((jaw_run / "analysis" / "analysis.json").read_text())


def _case_ports(run):
    """The jaw gripper's ports as its case file declares them, and where its geometry puts
    their points: ``(ports, {region: (x, y)})``."""
    from pacto_ng.case import get_case

    case = get_case("jaw-gripper")
    params = case.parameters(json.loads((run / "params.json").read_text())["params"])
    points = {v.name: (v.p.x, v.p.y) for v in case.geometry(params).vertices if v.name}
    return case.make_setup(params).ports, points


def test_analysis_holds_delta_and_both_ports(analysis):
    assert [r["pressure"] for r in analysis["pressures"]] == PRESSURES
    assert [p["region"] for p in analysis["settings"]["output_ports"]] == list(PORTS)
    for row in analysis["pressures"]:
        for kind in ("darcy", "fixed", "follower"):
            assert row[kind]["converged"]
            assert set(row[kind]["ports"]) == set(PORTS)
            assert all(np.isfinite(v) for v in row[kind]["ports"].values())
            assert np.isfinite(row[kind]["delta"])
    choice = analysis["settings"]["threshold_choice"]
    assert choice["reaches_output"] is True and choice["ports"] == dict.fromkeys(PORTS, True)
    assert set(analysis["part"]["port_shifts"]) == set(PORTS)
    assert analysis["part"]["output_port_shift"] == max(analysis["part"]["port_shifts"].values())
    for row in analysis["pressures"]:  # every port's displacement vector, d·u along it
        for kind in ("darcy", "fixed", "follower"):
            for port in analysis["settings"]["output_ports"]:
                vec = row[kind]["vectors"][port["region"]]
                assert np.dot(port["direction"], vec) == pytest.approx(
                    row[kind]["ports"][port["region"]], rel=1e-12)


def test_delta_is_the_weighted_sum_read_from_the_displacement_field(jaw_run, analysis):
    """The follower state at the largest pressure (remeshed.vtu's u): Δ = Σ w d·u at the jaw
    tips, and each port's own d·u, evaluated here from the field and the case's ports."""
    import meshio

    assert analysis["deformed_state"] == {"kind": "follower", "pressure": PRESSURES[-1]}
    ref = meshio.read(jaw_run / "analysis" / "remeshed.vtu")
    ports, tips = _case_ports(jaw_run)
    assert {p.region for p in ports} == set(PORTS)
    row = analysis["pressures"][-1]["follower"]
    delta = 0.0
    for port in ports:
        dist = np.linalg.norm(ref.points[:, :2] - tips[port.region], axis=1)
        k = int(np.argmin(dist))
        assert dist[k] < 1e-9  # the part has a vertex at the jaw tip
        along = float(np.dot(port.direction, ref.point_data["u"][k, :2]))
        assert row["ports"][port.region] == pytest.approx(along, rel=1e-10)
        delta += port.weight * along
    assert row["delta"] == pytest.approx(delta, rel=1e-10)


def test_small_pressures_are_linear_and_expected_is_the_run_rescaled(jaw_run, analysis):
    summary = json.loads((jaw_run / "summary.json").read_text())
    rows = analysis["pressures"]
    run = analysis["run"]  # the run's design, and the same at the part's order (2)
    assert run["output_displacement_rebuilt"] == pytest.approx(
        summary["output_displacement"], rel=1e-8)
    assert run["expected_order"] == 2 and summary["parameters"]["order"] == 1
    for row in rows:  # a linear run: its two-port Δ scaled with the pressure
        assert row["expected"] == pytest.approx(
            run["output_displacement_at_order"] * row["pressure"] / summary["load"], rel=1e-8)
    # the part's analyses with the run's linear law at 1e2 and 1e3 Pa: the deformation-
    # independent ones exactly linear, the follower to within 1 % (Δ is a difference of the
    # two jaws' values, so its nonlinear part is relatively larger than theirs)
    assert analysis["settings"]["model"] == "linear"
    for kind in ("darcy", "fixed"):
        assert rows[1][kind]["delta"] / rows[0][kind]["delta"] == pytest.approx(10.0, rel=1e-8)
    assert rows[1]["follower"]["delta"] / rows[0]["follower"]["delta"] == pytest.approx(
        10.0, rel=1e-2)


def test_report_shows_every_port(jaw_run, analysis):
    report = (jaw_run / "analysis" / "report.md").read_text()
    assert "Every port's own displacement" in report
    for region in PORTS:
        assert f"follower `{region}`" in report
        assert format(analysis["pressures"][-1]["follower"]["ports"][region], ".4g") in report
    assert format(analysis["pressures"][-1]["follower"]["delta"], ".4g") in report


def test_export_and_compare_of_a_two_port_run(jaw_run, tmp_path, capsys):
    import pyvista as pv

    assert main(["export", str(jaw_run), "--format", "stl", "--out", str(tmp_path / "p.stl"),
                 "--quiet"]) == 0
    stl = pv.read(tmp_path / "p.stl").clean()
    assert stl.n_open_edges == 0 and stl.volume > 0
    assert main(["compare", str(jaw_run), "--out", str(tmp_path / "cmp.png")]) == 0
    assert (tmp_path / "cmp.png").stat().st_size > 0
    assert "jaw-gripper" in capsys.readouterr().out
