"""What ``pacto analyse`` writes about a part (post.report): analysis.json, analysis.csv and
report.md from the sweeps, in one layout (the files of a whole analysis: test_cli_post.py,
test_analyse.py)."""
import csv
import io
import json

import numpy as np
import pytest

from pacto_ng.physics.loads import Port
from pacto_ng.post.part_entries import part_warnings
from pacto_ng.post.report import analysis_csv, analysis_json
from pacto_ng.post.report_md import report_md

PORT = Port("output", (0.0, -1.0), 1e4)


def _data(chamber_remeshed, chamber_sweeps, expected=True):
    th, rm = chamber_remeshed
    pressures = [1e3, 1e4, 1e5]
    exp = [dict(pressure=P, delta=4e-10 * P, converged=True, newton_iterations=1)
           for P in pressures] if expected else None
    run = {"as_built": not expected, "case": "chamber", "model": "linear", "load": 1e5,
           "load_unit": "Pa", "dim": 2, "dir": "x", "design": "x", "iterations": 1,
           "stopped": "iterations", "output_displacement_summary": 4e-5,
           "output_displacement_rebuilt": 4e-5, "load_path_note": None}
    settings = dict(threshold=0.5, threshold_choice={"note": "threshold 0.5"}, maxh=0.003,
                    model="neohookean", material="", E=1e8, nu=0.4, thickness=1e-3,
                    plane="strain", order=2, formulation="displacement", pressures=pressures,
                    supports={"clamp": ["fixed"]}, output_ports=[
                        {"region": "output", "direction": [0.0, -1.0], "spring": 1e4,
                         "weight": 1.0}])
    part = {"measure_unit": "m²", "measure": rm.area, "design_measure": th.area,
            "elements": rm.mesh.ne, "geometry": rm.geometry, "wetted": rm.wetted_length,
            "measures": {"remeshed": rm.area}, "port_shifts": {"output": 0.0}}
    return analysis_json(run=run, settings=settings, part=part, seal=None, materials=None,
                         sweeps=chamber_sweeps, ports=(PORT,), expected=exp,
                         deformed={"kind": "follower", "pressure": 1e5}, warnings=[], wall=1.0)


def test_analysis_json_csv_and_report_agree(chamber_remeshed, chamber_sweeps):
    data = json.loads(json.dumps(_data(chamber_remeshed, chamber_sweeps)))  # JSON-able
    assert data["settings"]["kinds"] == ["fixed", "follower"]
    for i, row in enumerate(data["pressures"]):
        for kind, sw in chamber_sweeps.items():
            pt = sw.points[i]
            assert row[kind]["delta"] == pt.delta and row[kind]["converged"]
            assert row[kind]["ports"] == {"output": pt.ports[0]}
            assert row[kind]["vectors"]["output"] == list(pt.vectors[0])
            assert row[kind]["min_J"] == pt.min_j and row[kind]["max_u"] == pt.max_u
    # the gaps: (analysed - expected)/|expected| at the largest and the smallest pressure
    for key, i in (("gap_at_largest_pressure", -1), ("gap_at_smallest_pressure", 0)):
        row = data["pressures"][i]
        for kind in ("fixed", "follower"):
            assert data[key][kind] == pytest.approx(
                (row[kind]["delta"] - row["expected"]) / abs(row["expected"]), rel=1e-14)
    rows = list(csv.DictReader(io.StringIO(analysis_csv(data))))
    assert [(r["kind"], float(r["pressure"])) for r in rows] == [
        (k, P) for k in ("fixed", "follower") for P in (1e3, 1e4, 1e5)]
    for r, (kind, i) in zip(rows, [(k, i) for k in ("fixed", "follower") for i in range(3)]):
        assert float(r["delta"]) == chamber_sweeps[kind].delta[i]
        assert float(r["port_output"]) == chamber_sweeps[kind].points[i].ports[0]
        assert float(r["u_output_y"]) == chamber_sweeps[kind].points[i].vectors[0][1]
    md = report_md(data)
    for section in ("## The part", "## The seal", "## The analyses", "## The gap",
                    "## Warnings", "## Pictures"):
        assert section in md
    assert format(data["pressures"][-1]["follower"]["delta"], ".4g") in md
    assert "![analysis](analysis.png)" in md and "![deformed](deformed.png)" in md
    # every row of the table has as many columns as its header
    table = [ln for ln in md.splitlines() if ln.startswith("| P |")]
    head = table[0].replace("\\|", "").count("|")  # (an escaped pipe is no column)
    body = md.split(table[0])[1].splitlines()[1:5]
    assert all(ln.count("|") == head for ln in body), body


def test_a_3d_run_s_report_shows_the_same_pictures(chamber_remeshed, chamber_sweeps):
    """report.md of a 3D run's part (one flow, report_md): the run's design.png and
    pressure.png (a 3D run writes both: the iso-surface and the mid-depth cut), the analysis
    and the deformed part, and the part's tetrahedra; an as-built part has no run pictures."""
    data = _data(chamber_remeshed, chamber_sweeps)
    data["run"]["dim"] = 3
    md = report_md(data)
    for picture in ("![design](../design.png)", "![pressure](../pressure.png)",
                    "![analysis](analysis.png)", "![deformed](deformed.png)"):
        assert picture in md
    assert "tetrahedra" in md and "triangles" not in md
    as_built = report_md(_data(chamber_remeshed, chamber_sweeps, expected=False))
    assert "../design.png" not in as_built


def test_a_part_as_built_has_no_expected_and_no_gap(chamber_remeshed, chamber_sweeps):
    data = _data(chamber_remeshed, chamber_sweeps, expected=False)
    assert data["gap_at_largest_pressure"] is None and data["gap_at_smallest_pressure"] is None
    assert all(r["expected"] is None for r in data["pressures"])
    assert "expected" not in data["definitions"] and "darcy" not in data["definitions"]
    md = report_md(data)
    assert "as built" in md and "No expected Δ" in md


def test_warnings_name_what_the_figures_hide(chamber_remeshed, chamber_sweeps):
    """An output point the part does not reach (more than two design elements away) and a
    port that moves more across its direction than along it."""
    from pacto_ng.post.part import Part

    th, rm = chamber_remeshed
    part = Part(rm.mesh, 2, 0.5, {}, rm.area, th.area, rm.wetted_length, None, "traced", None,
                (th, rm), {"output": ((0.05, 0.005), (0.05, 0.02))})
    vx, vy = chamber_sweeps["follower"].points[-1].vectors[0]
    across = Port("output", (vy, -vx))  # at right angles to the port's motion
    out = part_warnings(part, (across,), chamber_sweeps, "follower", h=0.001, unit="Pa")
    assert any("does not reach the output point 'output'" in w for w in out)
    assert any("moves more across its direction" in w for w in out)
    along = Port("output", (vx, vy))  # along it: no warning (nor with a coarse design)
    assert not part_warnings(part, (along,), chamber_sweeps, "follower", h=0.1, unit="Pa")
    assert np.isfinite(chamber_sweeps["follower"].delta).all()


def test_a_pressure_maximum_is_recorded_and_reported(chamber_remeshed, chamber_sweeps):
    """A sweep that passed a pressure maximum (its ``peak``, a point reached past it): in
    analysis.json's ``pressure_maximum`` and the point's ``past_peak``, and one line of
    report.md with both; a sweep without one records None and says nothing."""
    import dataclasses

    follower = chamber_sweeps["follower"]
    passed = dataclasses.replace(follower, peak={"pressure": 5e4, "delta": 2e-5},
                                 points=follower.points[:2] + [dataclasses.replace(
                                     follower.points[2], past_peak=True)])
    data = json.loads(json.dumps(_data(chamber_remeshed, dict(chamber_sweeps,
                                                              follower=passed))))
    assert data["pressure_maximum"] == {"fixed": None,
                                        "follower": {"pressure": 5e4, "delta": 2e-5}}
    assert [r["follower"]["past_peak"] for r in data["pressures"]] == [False, False, True]
    lines = [ln for ln in report_md(data).splitlines() if "pressure maximum" in ln]
    assert len(lines) == 1 and "50000 Pa at Δ = 2e-05 m" in lines[0]
    assert "reached past it: 1e+05." in lines[0]
    plain = report_md(json.loads(json.dumps(_data(chamber_remeshed, chamber_sweeps))))
    assert "A pressure maximum" not in plain
