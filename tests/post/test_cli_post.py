"""pacto analyse / export / compare on a small real run (pa-inverter, 1e5 Pa, coarse mesh).

The run and its analysis are made once per session (about 15 s on the shared machine); every
check reads what the commands wrote and recomputes what it can on its own (areas from the
written triangles, the STL's closedness and volume with pyvista, the Gmsh file read back by
Netgen).  The thesis check of §6.1.1 (linear vs Neo-Hookean design) is a benchmark,
benchmarks/post_thesis_check.py, not a test (see the end of this file).
"""
import json
import shutil
import subprocess
import sys

import numpy as np
import pytest

from pacto_ng.cli import main

pytestmark = pytest.mark.usefixtures("pacto_one_thread")

PRESSURES = [1e2, 1e3, 1e4, 1e5]
FILES = ("analysis.json", "analysis.csv", "analysis.png", "deformed.png", "report.md",
         "part.stl", "remeshed.vtu", "deformed.vtu")


def _serial(argv):
    """main(argv) on one thread: these systems are small, and two threads on the shared,
    loaded 2-core machine took 3-5x longer (measured: run + analyse 95 s instead of 20 s)."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("PACTO_THREADS", "1")
        return main(argv)


@pytest.fixture(scope="session")
def pa_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("cli_post") / "pa"
    # the filter radius pinned to three elements: a smooth 15-iteration design that holds on to
    # the clamp whatever the case's default radius for its finer mesh is
    # and no penalty continuation with a large move limit, so that 15 iterations give a design
    # independent of the case's (slower, smoother) default continuation
    rc = _serial(["run", "pa-inverter", "--load", "1e5", "--maxh", "0.01", "--iterations", "15",
                  "--set", "filter_radius=0.03", "--set", "penal_start=0", "--set", "move=0.2",
                  "--out", str(out), "--quiet"])
    assert rc == 0
    return out


@pytest.fixture(scope="session")
def analysed(pa_run):
    # a 15-iteration design is still grey: threshold 0.35 keeps it one piece with the clamp
    rc = _serial(["analyse", str(pa_run), "--pressures", ",".join(map(str, PRESSURES)),
                  "--threshold", "0.35", "--quiet"])
    assert rc == 0
    return pa_run / "analysis", json.loads((pa_run / "analysis" / "analysis.json").read_text())


def _triangle_area(points, tris):
    p = np.asarray(points)[:, :2]
    u, v = p[tris[:, 1]] - p[tris[:, 0]], p[tris[:, 2]] - p[tris[:, 0]]
    return float(0.5 * np.abs(u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]).sum())


def _one_line_error(capsys):
    err = capsys.readouterr().err
    lines = [ln for ln in err.strip().splitlines() if ln.strip()]
    assert len(lines) == 1, err
    assert lines[0].startswith("pacto: error:")
    return lines[0]


# -- analyse ----------------------------------------------------------------------------------
def test_analyse_writes_every_file(analysed):
    import matplotlib.image as mpimg
    import meshio

    folder, data = analysed
    for name in FILES:
        assert (folder / name).stat().st_size > 0, name
    for name in ("analysis.png", "deformed.png"):
        img = mpimg.imread(folder / name)
        assert img.ndim == 3 and min(img.shape[:2]) > 200
    assert [r["pressure"] for r in data["pressures"]] == PRESSURES
    for r in data["pressures"]:
        for kind in ("darcy", "fixed", "follower"):
            assert r[kind]["converged"] and r[kind]["newton_iterations"] >= 1
            assert 0.0 < r[kind]["min_J"] <= 1.0 + 1e-6
            assert r[kind]["max_u"] >= abs(r[kind]["delta"])
    ref, dfm = meshio.read(folder / "remeshed.vtu"), meshio.read(folder / "deformed.vtu")
    for m in (ref, dfm):
        assert {"u", "p"} <= set(m.point_data) and {"J", "stress"} <= set(m.cell_data)
    np.testing.assert_allclose(dfm.points - ref.points, ref.point_data["u"], atol=1e-15)
    # the deformed state is the follower's at the largest pressure: Δ read back from the file
    port = np.array(data["part"]["points"]["output"]["new"])
    k = int(np.argmin(np.linalg.norm(ref.points[:, :2] - port, axis=1)))
    d = np.array(data["settings"]["output_ports"][0]["direction"])
    assert d @ ref.point_data["u"][k, :2] == pytest.approx(
        data["pressures"][-1]["follower"]["delta"], rel=1e-10)
    # the Darcy pressure on the part: the inlet pressure where the part touches the inlet, and
    # not above it (below 0 it may undershoot: Δs is a fifth of this mesh's elements)
    assert ref.point_data["p"].max() == pytest.approx(PRESSURES[-1], rel=1e-3)
    report = (folder / "report.md").read_text()
    assert "![analysis](analysis.png)" in report and "![deformed](deformed.png)" in report
    assert format(data["pressures"][-1]["follower"]["delta"], ".4g") in report


def test_expected_is_the_run_rescaled_for_a_linear_design(pa_run, analysed):
    _, data = analysed
    summary = json.loads((pa_run / "summary.json").read_text())
    rows = data["pressures"]
    # the run's design rebuilt is the run's own output displacement; the expected Δ is that
    # design at the part's order (2) on the run's order-1 mesh: softer
    run = data["run"]
    assert run["output_displacement_rebuilt"] == pytest.approx(
        summary["output_displacement"], rel=1e-8)
    assert (run["expected_order"], summary["parameters"]["order"]) == (2, 1)
    assert rows[-1]["pressure"] == summary["load"]
    assert rows[-1]["expected"] == pytest.approx(run["output_displacement_at_order"], rel=1e-12)
    assert rows[-1]["expected"] > 1.01 * summary["output_displacement"]
    # linear model: the re-analysis at every pressure is the linear scaling
    ratio = [r["expected"] / r["pressure"] for r in rows]
    np.testing.assert_allclose(ratio, ratio[-1], rtol=1e-8)


def test_remeshed_area_within_2_percent_of_thresholded(analysed):
    import meshio

    folder, data = analysed
    m = meshio.read(folder / "remeshed.vtu")
    area = _triangle_area(m.points, m.cells_dict["triangle"])
    m = data["part"]["measures"]
    assert area == pytest.approx(m["remeshed"], rel=1e-10) == data["part"]["measure"]
    kept = m["thresholded"] - m["removed_specks"] - m["dropped_floating"]
    assert kept > 0
    assert abs(area - kept) / kept < 0.02


def test_part_stl_is_the_whole_closed_part_in_mm(pa_run, analysed):
    """part.stl (as every run writes it): the half as analysed and its mirror image about the
    symmetry line, extruded by t, in mm: volume 2 × the remeshed area × t."""
    import pyvista as pv

    folder, data = analysed
    t = json.loads((pa_run / "params.json").read_text())["params"]["thickness"]
    assert json.loads((pa_run / "summary.json").read_text())["symmetric_half_domain"]
    stl = pv.read(folder / "part.stl").clean()
    assert stl.n_open_edges == 0 and stl.is_manifold
    assert stl.volume == pytest.approx(2 * data["part"]["measures"]["remeshed"] * t * 1e9,
                                       rel=1e-6)
    assert np.ptp(stl.points[:, 2]) == pytest.approx(t * 1e3, rel=1e-6)  # float32


def test_follower_equals_fixed_at_vanishing_pressure(analysed):
    """The follower load differs from the fixed one by terms of order the strain: their
    relative difference must fall in proportion to the pressure."""
    _, data = analysed
    P = np.array([r["pressure"] for r in data["pressures"]])
    fix = np.array([r["fixed"]["delta"] for r in data["pressures"]])
    fol = np.array([r["follower"]["delta"] for r in data["pressures"]])
    rel = np.abs(fol - fix) / np.abs(fix)
    assert np.all(np.diff(rel) > 0)  # grows with the pressure
    assert rel[0] < 1e-5  # 100 Pa on E = 3e9 Pa
    np.testing.assert_allclose(rel / P, rel[-1] / P[-1], rtol=0.2)  # linear in P


# -- export -----------------------------------------------------------------------------------
def test_export_round_trips(pa_run, analysed, tmp_path):
    import meshio
    import ngsolve
    import pyvista as pv
    from netgen.read_gmsh import ReadGmsh

    folder, data = analysed
    area = data["part"]["measures"]["remeshed"]
    t = json.loads((pa_run / "params.json").read_text())["params"]["thickness"]
    ref = meshio.read(folder / "remeshed.vtu")
    for fmt in ("stl", "vtk", "msh"):
        assert main(["export", str(pa_run), "--format", fmt, "--out", str(tmp_path / f"p.{fmt}"),
                     "--no-mirror", "--units", "m", "--quiet"]) == 0  # the half, in metres
    stl = pv.read(tmp_path / "p.stl").clean()
    assert stl.n_open_edges == 0 and stl.volume == pytest.approx(area * t, rel=1e-6)
    vtk = meshio.read(tmp_path / "p.vtk")
    # the analysis's settings are reused: the same part as remeshed.vtu
    assert len(vtk.cells_dict["triangle"]) == len(ref.cells_dict["triangle"])
    assert _triangle_area(vtk.points, vtk.cells_dict["triangle"]) == pytest.approx(area, rel=1e-10)
    msh = ngsolve.Mesh(ReadGmsh(str(tmp_path / "p.msh")))
    assert ngsolve.Integrate(1.0, msh) == pytest.approx(area, rel=1e-10)
    assert {"fixed", "pressure", "free"} <= set(msh.GetBoundaries())
    wetted = ngsolve.Integrate(1.0, msh, definedon=msh.Boundaries("pressure"))
    assert wetted == pytest.approx(data["part"]["wetted"], rel=1e-10)
    assert data["part"]["boundaries"]["pressure"] == pytest.approx(wetted, rel=1e-10)


# -- compare ----------------------------------------------------------------------------------
def test_compare_writes_a_picture(pa_run, analysed, tmp_path, capsys):
    import matplotlib.image as mpimg

    other = tmp_path / "copy"
    shutil.copytree(pa_run, other, ignore=shutil.ignore_patterns("analysis"))
    out = tmp_path / "cmp.png"
    assert main(["compare", str(pa_run), str(other), "--out", str(out)]) == 0
    img = mpimg.imread(out)
    assert img.shape[0] > 300 and img.shape[1] > 600
    table = capsys.readouterr().out.splitlines()
    assert len(table) == 4 and "pa-inverter" in table[1] and "pa-inverter" in table[2]


def test_the_part_is_built_on_the_case_geometry(pa_run, analysed):
    """The rebuilt problem's shape reaches remesh: the analysed part runs along the case's own
    edges (geometry "domain"), with their names; the half domain's symmetry line (y = 0) is
    found for the whole-mechanism pictures."""
    from pacto_ng.post.compare import run_symmetry
    from pacto_ng.post.runs import load_run

    _, data = analysed
    assert data["part"]["geometry"] == "domain"
    line = run_symmetry(load_run(pa_run, "compare"))
    assert line is not None and line.direction == pytest.approx((1.0, 0.0))
    assert abs(line.point[1]) < 1e-15


# -- bad input: one line on stderr, exit 2 ------------------------------------------------------
@pytest.mark.parametrize("extra, field", [
    (["--threshold", "0"], "--threshold"),
    (["--threshold", "1"], "--threshold"),
    (["--threshold", "1.5"], "--threshold"),
    (["--pressures", "1e5,abc"], "--pressures"),
    (["--pressures", "-1e5"], "--pressures"),
    (["--pressures", ""], "--pressures"),
])
def test_bad_options_exit_2(pa_run, extra, field, capsys):
    assert main(["analyse", str(pa_run), *extra]) == 2
    assert field in _one_line_error(capsys)


def test_folder_without_a_finished_run_exits_2(pa_run, tmp_path, capsys):
    assert main(["analyse", str(tmp_path / "missing")]) == 2
    assert "not a folder" in _one_line_error(capsys)
    assert main(["analyse", str(tmp_path)]) == 2
    assert "holds no run" in _one_line_error(capsys)
    shutil.copy(pa_run / "params.json", tmp_path / "params.json")  # started, no summary yet
    for cmd in (["analyse", str(tmp_path)], ["export", str(tmp_path), "--format", "stl"],
                ["compare", str(tmp_path)]):
        assert main(cmd) == 2
        assert "no finished run" in _one_line_error(capsys)


def test_design_without_solid_on_the_clamp_exits_2(pa_run, tmp_path, capsys):
    """The final design replaced by a block far from the clamp (the passive block at the clamp
    is smaller than the speck limit and is removed)."""
    from pacto_ng.case import build_problem, get_case

    run = tmp_path / "floating"
    shutil.copytree(pa_run, run, ignore=shutil.ignore_patterns("analysis"))
    info = json.loads((run / "params.json").read_text())
    case = get_case(info["case"])
    problem = build_problem(case, case.parameters(info["params"]))
    c = problem.field.centroids()[problem.field.design_index]
    x = ((c[:, 0] > 0.12) & (c[:, 0] < 0.19) & (c[:, 1] > 0.01) & (c[:, 1] < 0.06)).astype(float)
    with np.load(run / "checkpoint.npz") as d:
        arrays = {k: d[k] for k in d.files}
    arrays["x"] = x
    np.savez(run / "checkpoint.npz", **arrays)
    assert main(["analyse", str(run), "--quiet"]) == 2
    assert "no solid touches the clamp" in _one_line_error(capsys)
    assert main(["export", str(run), "--format", "stl"]) == 2
    assert "no solid touches the clamp" in _one_line_error(capsys)


def test_a_remesh_too_large_for_the_machine_is_refused_before_netgen(pa_run, capsys,
                                                                    monkeypatch):
    """--maxh 1e-6 on the pa-inverter's part (billions of triangles): analyse and export stop
    with one line naming --maxh, exit 2, before Netgen is asked for the part's mesh (its call
    is recorded here) and with nothing written to the run's folder."""
    import importlib

    remesh = importlib.import_module("pacto_ng.post.remesh")  # the module, not the function
    calls = []
    monkeypatch.setattr(remesh, "_generate", lambda *args: calls.append(args))
    before = {p: p.read_bytes() for p in pa_run.rglob("*") if p.is_file()}
    for cmd, words in ((["analyse", str(pa_run), "--maxh", "1e-6", "--quiet"],
                        ("displacement dofs at order 2", "memory", "lower --order")),
                       (["export", str(pa_run), "--format", "stl", "--maxh", "1e-6"],
                        ("the mesh alone needs", "the run's setting"))):
        assert main(cmd) == 2
        line = _one_line_error(capsys)
        assert line.startswith("pacto: error: --maxh = 1e-06: about ") and "triangles" in line
        assert "Netgen" in line and "give a larger --maxh" in line
        for w in words:
            assert w in line, line
    assert calls == []
    assert {p: p.read_bytes() for p in pa_run.rglob("*") if p.is_file()} == before


def test_the_part_mesh_estimate_is_near_netgens_count(pa_run, analysed):
    """The estimate behind that refusal (from the design's solid area Σ a ρ̄ at the analysis's
    maxh) against the triangles Netgen made of the analysed part: within a factor 2 (measured
    0.80: the threshold was lowered to 0.295, a part larger than Σ a ρ̄)."""
    from pacto_ng import resources
    from pacto_ng.post.runs import load_run, rebuild
    from pacto_ng.threads import compute

    _, summary = analysed
    with compute():
        problem = rebuild(load_run(pa_run, "analyse"))
    area = float(problem.field.areas @ problem.values["rho_bar"])
    est = resources.estimate_part(area, summary["settings"]["maxh"], 2, dim=2)
    real = summary["part"]["elements"]
    assert 0.5 < est.elements / real < 2.0, (est.elements, real)


def test_non_pressure_case_exports_but_is_not_analysed(tmp_path, capsys):
    import pyvista as pv

    run = tmp_path / "cantilever"
    assert main(["run", "cantilever", "--maxh", "0.05", "--iterations", "3", "--out", str(run),
                 "--quiet"]) == 0
    assert main(["analyse", str(run)]) == 2
    assert "pressure cases only" in _one_line_error(capsys)
    assert main(["export", str(run), "--format", "stl", "--quiet"]) == 0
    stl = pv.read(run / "export" / "design.stl").clean()
    assert stl.n_open_edges == 0 and stl.volume > 0


def test_cli_end_to_end_one_line(pa_run):
    """The installed entry point: the error is one line, no traceback."""
    r = subprocess.run([sys.executable, "-m", "pacto_ng.cli", "analyse", str(pa_run),
                        "--threshold", "2"], capture_output=True, text=True, timeout=300)
    assert r.returncode == 2
    assert r.stderr.strip().count("\n") == 0 and "--threshold" in r.stderr
    assert "Traceback" not in r.stderr


# -- the thesis check ------------------------------------------------------------------------
# Not a test: it needs four pa-inverter optimisations, and the Neo-Hookean ones take 10-40 min
# each on the shared machine (the one at 1e7 Pa currently stops on a Newton failure at iteration
# 56).  It is benchmarks/post_thesis_check.py; its measured figures are in docs/postprocessing.md.


def test_analyse_records_its_threshold_choice(analysed):
    """The threshold asked (0.35) and the one used: equal when the part kept on the clamp
    contains the output point, lower otherwise; the record and the report say which."""
    folder, data = analysed
    ch = data["settings"]["threshold_choice"]
    assert ch["requested"] == 0.35 and ch["start"] == 0.35 and ch["connect"] is True
    assert data["settings"]["threshold"] == ch["used"] <= 0.35
    assert ch["reaches_output"] is True and not ch["missed"]
    assert ch["lowered"] == (ch["used"] < 0.35)
    assert ch["part_area"] == pytest.approx(data["part"]["measures"]["thresholded"], rel=1e-12)
    assert 0 < ch["design_volume"] < ch["part_area"] * 2
    # the output point lies in the part: the remeshed part's nearest vertex is within an element
    assert data["part"]["output_port_shift"] < data["run"]["mesh_h"]
    assert "The threshold: threshold 0.35" in (folder / "report.md").read_text()


def test_analyse_retries_a_part_netgen_cannot_mesh(pa_run, tmp_path, monkeypatch):
    """A Netgen failure at the chosen threshold is retried 0.005 lower (the part keeps its
    pieces and the output point): the record says at which threshold it was meshed.  The
    failure is simulated on the first attempt (measured on a PneuNet part at 0.4594, meshed at
    0.4544)."""
    from pacto_ng.post import part as part_module
    from pacto_ng.post.analyse import analyse_run

    run = tmp_path / "retry"
    shutil.copytree(pa_run, run, ignore=shutil.ignore_patterns("analysis"))
    real, calls = part_module.remesh, []

    def flaky(th, *args, **kw):
        calls.append(th.threshold)
        if len(calls) == 1:
            raise ValueError("Netgen could not mesh the part: simulated; threshold x, maxh y")
        return real(th, *args, **kw)

    monkeypatch.setattr(part_module, "remesh", flaky)
    assert analyse_run(run, pressures=[1e5], threshold_value=0.35, kinds=("fixed",),
                       quiet=True) == 0
    ch = json.loads((run / "analysis" / "analysis.json").read_text())["settings"]["threshold_choice"]
    assert len(calls) == 2 and calls[1] == pytest.approx(calls[0] - 0.005)
    assert ch["used"] == calls[1] and ch["mesh_retries"] == 1 and "meshed at" in ch["note"]


def test_another_model_for_the_part_of_a_linear_run(pa_run, analysed, tmp_path):
    """``--model neohookean`` on a linear run: the part is analysed with the Neo-Hookean law
    (Newton iterates), the expected Δ is still the run's own (linear) one; the Neo-Hookean Δ
    leaves the linear analysis of the same part in proportion to the pressure, the
    geometrically nonlinear term (measured 2.1e-6 at 100 Pa, 2.1e-3 at 1e5 Pa: the thin
    hinges of a 15-iteration design rotate)."""
    _, linear = analysed
    run = tmp_path / "nh"
    shutil.copytree(pa_run, run, ignore=shutil.ignore_patterns("analysis"))
    assert main(["analyse", str(run), "--pressures", "1e2,1e5", "--threshold", "0.35",
                 "--kinds", "fixed", "--model", "neohookean", "--quiet"]) == 0
    data = json.loads((run / "analysis" / "analysis.json").read_text())
    assert data["settings"]["model"] == "neohookean" and data["run"]["model"] == "linear"
    assert data["part"]["elements"] == linear["part"]["elements"]  # the same part
    lin = {r["pressure"]: r for r in linear["pressures"]}
    for r in data["pressures"]:
        assert r["expected"] == pytest.approx(lin[r["pressure"]]["expected"], rel=1e-12)
        assert r["fixed"]["converged"] and r["fixed"]["newton_iterations"] >= 2
        assert lin[r["pressure"]]["fixed"]["newton_iterations"] == 1  # the linear one solve
    small, large = (r["fixed"]["delta"] / lin[r["pressure"]]["fixed"]["delta"] - 1.0
                    for r in data["pressures"])
    print("neohookean against linear at 1e2 and 1e5 Pa:", small, large)
    assert 1e-5 < abs(large) < 1e-2
    assert small / large == pytest.approx(1e2 / 1e5, rel=0.1)
    assert "Model `neohookean`" in (run / "analysis" / "report.md").read_text()


def test_an_analysis_that_would_take_too_long_is_refused_with_its_estimate(pa_run, capsys):
    """--time-limit 1: the analysis of the pa-inverter part (a few seconds) is refused before
    anything is meshed or written, with one line giving the estimated time and memory."""
    before = {p: p.read_bytes() for p in pa_run.rglob("*") if p.is_file()}
    assert main(["analyse", str(pa_run), "--threshold", "0.35", "--time-limit", "1"]) == 2
    line = _one_line_error(capsys)
    for words in ("--maxh = ", "triangles", "displacement dofs at order 2",
                  "the analysis would take about", "Newton iterations", "GB of memory",
                  "longer than --time-limit 1 s", "give a larger --maxh"):
        assert words in line, line
    assert {p: p.read_bytes() for p in pa_run.rglob("*") if p.is_file()} == before
