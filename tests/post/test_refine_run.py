"""``pacto refine RUN`` (pacto_ng/post/refine_run.py): the part of a finished 2D pressure run,
its shape refined for a larger output at no more volume.

The run: pneunet on a coarse mesh (maxh 4 mm), one iteration, its final design replaced by
the solid member (small_cases.run_with_design: every design element solid, the chamber a
passive void), so that the part is the whole sealed member with its output point and the
run's output spring there.  Three steps of the refinement are checked for what the command
promises a user: the files, Δ larger than the part as made, the volume near the part's own
starting volume (the bound), the part inside the run's design domain (no warning), the
progress lines, the last line, and the refusals (an
existing RUN/refine, a 3D run, a case without pressure) in one line with exit code 2.

Measured (3 steps, one thread, the part kept in the design domain's box): Δ 3.52e-6 →
5.23e-5 m (the solid member barely bends; the boundary moves where it bends it most), volume
1.4 % below the bound (on pneunet's optimised part, 20 steps end 0.2 % below it), lowest
Jacobian 0.33, no warning; the refinement about 1.3 s.
"""
import csv
import json
import shutil

import numpy as np
import pytest

from pacto_ng.cli import main
from pacto_ng.commands import why_not_refined

pytestmark = pytest.mark.usefixtures("pacto_one_thread")

FILES = ("history.csv", "summary.json", "refined.vtu", "refined.png", "refined.stl")


@pytest.fixture(scope="module")
def solid_member(tmp_path_factory):
    from small_cases import run_with_design

    return run_with_design(tmp_path_factory.mktemp("refine") / "pn",
                           ["pneunet", "--maxh", "0.004", "--iterations", "1", "--no-part"],
                           lambda c: np.ones(len(c), dtype=bool))


@pytest.fixture(scope="module")
def refined(solid_member):
    """``(run folder, exit code, printed lines)`` of ``pacto refine RUN --steps 3``."""
    import contextlib
    import io

    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        code = main(["refine", str(solid_member), "--steps", "3", "--pressures", "5e4,1e5"])
    return solid_member, code, out.getvalue().strip().splitlines()


def test_refine_writes_its_files_and_raises_the_output(refined):
    run, code, lines = refined
    assert code == 0
    folder = run / "refine"
    for name in FILES:
        assert (folder / name).stat().st_size > 0, name
    s = json.loads((folder / "summary.json").read_text())
    assert s["status"] == "steps" and s["steps"] == 3
    assert (s["model"], s["load_type"], s["load"]) == ("linear", "fixed", 1e5)
    assert s["delta_after"] > s["delta_before"] > 0.0
    assert s["gain"] == pytest.approx((s["delta_after"] - s["delta_before"])
                                      / s["delta_before"])
    # the bound is the part's own starting volume; three steps leave it 1.4 % below (measured)
    assert s["volume_bound"] == pytest.approx(s["volume_before"], rel=1e-12)
    assert abs(s["volume_after"] / s["volume_bound"] - 1.0) <= 0.05
    assert 0.3 <= s["lowest_det"] < 1.0
    # a mechanism run (pneunet minimises -Δ/SE): its ratio is held at the part's own, to the
    # augmented Lagrangian's slack (measured: 0.0 % after three steps)
    r = s["ratio"]
    assert r["after"] >= 0.98 * r["before"] > 0.0
    assert s["warnings"] == []  # the refinement keeps the part in the design domain
    with open(folder / "history.csv") as f:
        rows = list(csv.DictReader(f))
    assert [int(r["step"]) for r in rows] == [0, 1, 2, 3]
    assert set(rows[0]) == {"step", "mesh", "delta", "ratio", "volume", "det", "length",
                            "wall", "merit"}
    assert float(rows[-1]["delta"]) == pytest.approx(s["delta_after"], rel=1e-9)
    assert all(float(b["merit"]) < float(a["merit"]) for a, b in zip(rows, rows[1:]))
    # one progress line per step, and the last line
    assert sum(line.strip().startswith("step ") for line in lines) == 3
    assert lines[-1].startswith("refined: Δ ") and "status steps" in lines[-1]
    assert lines[-1].endswith(f"— {folder}")


def test_the_refined_part_is_checked_on_an_independent_remesh(refined):
    """summary.json's ``check``: the refined shape meshed afresh (finer, other vertices) and
    analysed again gives the refinement's Δ to 2 % (the goal the refinement is held to)."""
    run, _, lines = refined
    s = json.loads((run / "refine" / "summary.json").read_text())
    check = s["check"]
    assert check["maxh"] < s["part"]["maxh"] and check["elements"] > s["part"]["elements"]
    assert check["difference"] == pytest.approx(
        (check["delta"] - s["delta_after"]) / s["delta_after"], rel=1e-12)
    assert abs(check["difference"]) <= 0.02
    assert s["remeshes"] == 0  # three steps leave the mesh fit to move
    assert any(line.strip().startswith("an independent remesh of the refined part")
               for line in lines)


def test_the_refined_part_is_swept_over_the_pressures_asked(refined):
    """``--pressures 5e4,1e5``: the refined part analysed afresh at each pressure on its
    independent remesh, as ``pacto analyse`` analyses a part; at the run's load (1e5 Pa) that is the check's own analysis (the
    same Δ), and the run's model is linear with a fixed pressure, so Δ is proportional to
    the pressure (half at 5e4 Pa)."""
    run, _, lines = refined
    s = json.loads((run / "refine" / "summary.json").read_text())
    sweep = {entry["pressure"]: entry for entry in s["sweep"]}
    assert sorted(sweep) == [5e4, 1e5] and all(e["converged"] for e in sweep.values())
    assert sweep[1e5]["delta"] == pytest.approx(s["check"]["delta"], rel=1e-10)
    assert sweep[5e4]["delta"] == pytest.approx(0.5 * sweep[1e5]["delta"], rel=1e-9)
    assert sum(line.strip().startswith("fixed linear P = ") for line in lines) == 2


def test_the_refined_stl_is_the_whole_part_closed_in_mm(refined):
    """refined.stl: a closed surface (every edge shared by two triangles) in mm, whose
    enclosed volume is the refined part's (PneuNet's member has no symmetry line, so the
    part is whole as it is) to the polygon's exactness."""
    import pyvista as pv

    run, _, _ = refined
    s = json.loads((run / "refine" / "summary.json").read_text())
    surface = pv.read(run / "refine" / "refined.stl")
    assert surface.n_open_edges == 0
    assert surface.volume * 1e-9 == pytest.approx(s["volume_after"], rel=1e-6)


def test_the_refined_vtu_is_the_moved_part(refined):
    """refined.vtu: the part's vertices at their moved positions, with u and the motion;
    the clamp (x = 0) does not move, the boundary elsewhere does."""
    import meshio

    run, _, _ = refined
    m = meshio.read(run / "refine" / "refined.vtu")
    moved = m.point_data["moved"]
    reference = m.points - moved
    on_clamp = np.abs(reference[:, 0]) < 1e-9
    assert on_clamp.any() and np.all(moved[on_clamp] == 0.0)
    assert np.max(np.linalg.norm(moved, axis=1)) > 1e-4  # a tenth of a millimetre at least
    assert np.all(np.isfinite(m.point_data["u"])) and np.any(m.point_data["u"])


def test_the_refined_part_lies_in_the_design_domain(refined):
    """Every moved vertex of refined.vtu lies in the bounding box of the run's design mesh
    (design.vtu) to 1e-12 of its size."""
    import meshio

    run, _, _ = refined
    domain = meshio.read(run / "design.vtu").points[:, :2]
    low, high = domain.min(axis=0), domain.max(axis=0)
    moved = meshio.read(run / "refine" / "refined.vtu").points[:, :2]
    tol = 1e-12 * float(np.max(high - low))
    assert np.all(moved >= low - tol) and np.all(moved <= high + tol)


def test_an_existing_refine_folder_is_refused_and_kept(refined, capsys):
    run, _, _ = refined
    before = {n: (run / "refine" / n).read_bytes() for n in FILES}
    capsys.readouterr()
    assert main(["refine", str(run), "--steps", "1", "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--overwrite" in err[0]
    assert {n: (run / "refine" / n).read_bytes() for n in FILES} == before


def test_a_3d_part_is_refined_checked_and_written(tmp_path_factory, capsys):
    """pneunet-3d on a coarse mesh (maxh 6 mm, no inlet wall), one iteration, its design
    replaced by the solid lower part (as tests/post/test_3d_post.py makes it), refined for two
    steps without a wall floor: Δ grows (measured 3.7e-8 → 3.7e-6 m: the block barely bends
    at first), the independent remesh (a new interior for the same surface, finer) gives the
    refinement's Δ to 2 % (measured -1.94 %; with the default floor -2.55 %, Δ 2.0e-6 m: on
    this block of 1035 elements the check is a coarse mesh's, the floor's own tests are
    test_a_wall_floor_is_kept_and_the_thinnest_wall_reported and tests/shape/
    test_thickness.py), refined.vtu holds tetrahedra, and refined.stl is the whole part,
    closed, in mm: its volume twice the half's (pneunet-3d is solved on its half in z: one
    symmetry plane) to the STL's single precision."""
    import meshio
    import pyvista as pv
    from small_cases import run_with_design

    run = run_with_design(tmp_path_factory.mktemp("refine3d") / "pn",
                          ["pneunet-3d", "--maxh", "0.006", "--iterations", "1", "--no-part",
                           "--set", "filter_radius=0.004", "--set", "inlet_wall=0"],
                          lambda c: c[:, 1] < 0.03)
    capsys.readouterr()
    assert main(["refine", str(run), "--steps", "2", "--min-wall", "0"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert lines[-1].startswith("refined: Δ ")
    folder = run / "refine"
    s = json.loads((folder / "summary.json").read_text())
    assert s["steps"] == 2 and s["delta_after"] > s["delta_before"] > 0.0
    assert abs(s["check"]["difference"]) <= 0.02
    assert s["warnings"] == []
    # the thinnest wall, measured in 3D too: no thicker than the half's depth (15 mm)
    walls = s["thinnest_wall"]
    assert 0 < walls["part_as_made"] < 0.015 and 0 < walls["refined"] < 0.015
    assert list(meshio.read(folder / "refined.vtu").cells_dict) == ["tetra"]
    surface = pv.read(folder / "refined.stl")
    assert surface.n_open_edges == 0
    assert surface.volume * 1e-9 == pytest.approx(2.0 * s["volume_after"], rel=1e-5)
    assert (folder / "refined.png").stat().st_size > 10_000


def test_a_case_without_pressure_and_a_missing_run_are_refused(tmp_path, capsys):
    out = tmp_path / "cantilever"
    assert main(["run", "cantilever", "--nelx", "20", "--nely", "10", "--iterations", "1",
                 "--no-part", "--quiet", "--out", str(out)]) == 0
    capsys.readouterr()
    assert main(["refine", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no wall pressure" in err[0]
    assert not (out / "refine").exists()
    assert main(["refine", str(tmp_path / "nowhere"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "is not a folder" in err[0]


def test_overwrite_replaces_the_files_and_nothing_else(solid_member, tmp_path, capsys):
    """--overwrite on a copy of the refined run: its files rewritten (0 steps: the part as
    made), a file of the user's in RUN/refine kept; --quiet prints the last line only."""
    import shutil

    run = tmp_path / "copy"
    shutil.copytree(solid_member, run)
    (run / "refine").mkdir(exist_ok=True)
    (run / "refine" / "notes.txt").write_text("mine")
    capsys.readouterr()
    assert main(["refine", str(run), "--steps", "0", "--quiet", "--overwrite"]) == 0
    printed = capsys.readouterr().out.strip().splitlines()
    assert len(printed) == 1 and printed[0].startswith("refined: Δ ")
    s = json.loads((run / "refine" / "summary.json").read_text())
    assert s["steps"] == 0 and s["delta_after"] == s["delta_before"]
    assert (run / "refine" / "notes.txt").read_text() == "mine"


def test_check_gradients_on_the_runs_part(solid_member, capsys):
    """``pacto refine RUN --check-gradients``: Δ, the volume and Δ/SE (pneunet is a
    mechanism run) against central differences in two directions, every relative error
    within 1e-5 (measured on the default pneunet run: at most 4.4e-7), exit code 0, nothing
    written; a bad --directions is one line with exit code 2."""
    before = sorted(p.name for p in solid_member.rglob("*"))
    assert main(["refine", str(solid_member), "--check-gradients", "--directions", "2"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    errors = [float(line.rsplit("relative error ", 1)[1]) for line in lines
              if line.startswith("  direction ")]
    assert len(errors) == 6 and max(errors) <= 1e-5
    assert lines[-1].startswith(f"refine {solid_member} --check-gradients: the largest "
                                f"relative error") and "within 1e-05" in lines[-1]
    assert "Δ, volume, Δ/SE" in lines[-1]
    assert sorted(p.name for p in solid_member.rglob("*")) == before
    assert main(["refine", str(solid_member), "--check-gradients", "--directions", "0"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--directions" in err[0]



def test_resume_ends_with_the_refined_part(solid_member, tmp_path, capsys):
    """``pacto resume DIR`` (as ``pacto run``; a pressure case with an output port): one more
    iteration from the solid member, its part made, then refined into DIR/refine/ (20 steps
    by default); the refinement's last line follows the part's, and its summary compares the
    refined Δ with the design's as the part line does (``gap``); with ``--no-refine`` the
    run ends with the part."""
    import shutil

    run = tmp_path / "pn"
    shutil.copytree(solid_member, run, ignore=shutil.ignore_patterns("refine"))
    capsys.readouterr()
    assert main(["resume", str(run), "--iterations", "2", "--no-refine"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert lines[-1].startswith("part: ") and not (run / "refine").exists()
    assert main(["resume", str(run), "--iterations", "3"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert lines[-1].startswith("refined: Δ ")
    part = [k for k, line in enumerate(lines) if line.startswith("part: ")]
    assert part and part[-1] < len(lines) - 1
    s = json.loads((run / "refine" / "summary.json").read_text())
    entry = json.loads((run / "summary.json").read_text())["part"]
    assert s["steps"] == 20 or s["status"] != "steps"
    assert s["design_delta"] == entry["output_displacement_design"]
    assert s["gap"] == pytest.approx((s["delta_after"] - s["design_delta"])
                                     / abs(s["design_delta"]), rel=1e-12)
    assert "the design promised" in lines[-1]


def test_another_loading_is_the_one_reported(solid_member, tmp_path):
    """``--model neohookean --load-type follower --load 5e4``: summary.json (whose loading
    refined.png's title states) names the refinement's own loading, not the run's (linear,
    fixed)."""
    import shutil

    run = tmp_path / "pn"
    shutil.copytree(solid_member, run)
    assert main(["refine", str(run), "--steps", "1", "--model", "neohookean",
                 "--load-type", "follower", "--load", "5e4", "--quiet", "--overwrite"]) == 0
    s = json.loads((run / "refine" / "summary.json").read_text())
    assert (s["model"], s["load_type"], s["load"]) == ("neohookean", "follower", 5e4)


def test_a_wall_floor_is_kept_and_the_thinnest_wall_reported(solid_member, tmp_path, capsys):
    """The wall floor: by default and with ``--min-wall 0`` none, ``--min-wall T`` T;
    summary.json reports the thinnest wall as made and refined and the floor with where it
    came from, no shape of history.csv has a wall below the floor; a floor that is no length
    is refused in one line (exit 2)."""
    import shutil

    run = tmp_path / "pn"
    shutil.copytree(solid_member, run)

    def refined(*options):
        assert main(["refine", str(run), "--steps", "3", "--quiet", "--overwrite",
                     *options]) == 0
        with open(run / "refine" / "history.csv") as f:
            walls = [float(row["wall"]) for row in csv.DictReader(f)]
        s = json.loads((run / "refine" / "summary.json").read_text())["thinnest_wall"]
        assert walls[0] == pytest.approx(s["part_as_made"], rel=1e-12)
        assert walls[-1] == pytest.approx(s["refined"], rel=1e-9) and s["refined"] > 0
        return s, walls

    for options in ((), ("--min-wall", "0")):
        s, _ = refined(*options)
        assert s["floor"] is None and s["floor_from"] == "none"
    floor = 0.999 * s["part_as_made"]
    s, walls = refined("--min-wall", str(floor))
    assert s["floor"] == floor and s["floor_from"] == "--min-wall" and min(walls) >= floor * (1 - 1e-9)
    capsys.readouterr()
    assert main(["refine", str(run), "--min-wall", "-1", "--overwrite"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--min-wall" in err[0]


def test_a_nonlinear_2d_run_ends_with_its_refined_part(tmp_path, capsys):
    """``pacto resume`` (as ``pacto run``) under a nonlinear model in 2D, from the solid
    member: it ends with the part refined under that model (DIR/refine/)."""
    from small_cases import run_with_design

    run = run_with_design(tmp_path / "nh", ["pneunet", "--maxh", "0.004", "--iterations", "1",
                                            "--no-part", "--model", "neohookean"],
                          lambda c: np.ones(len(c), dtype=bool))
    capsys.readouterr()
    assert main(["resume", str(run), "--iterations", "2"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    summary = json.loads((run / "refine" / "summary.json").read_text())
    assert summary["model"] == "neohookean" and summary["steps"] > 0
    assert lines[-1].startswith("refined: ")


def test_which_parts_are_not_why_not_refined():
    """A part without an equilibrium at the run's load, and a 3D part under a nonlinear
    model (a line naming ``pacto refine DIR``); a 2D one under any model, a 3D linear one
    are refined."""
    assert "no equilibrium" in why_not_refined({"converged": False}, "linear", 2, "d")
    line = why_not_refined({"converged": True}, "neohookean", 3, "runs/x")
    assert "pacto refine runs/x refines it" in line and "neohookean" in line
    assert why_not_refined({"converged": True}, "wang", 2, "d") == ""
    assert why_not_refined({"converged": True}, "linear", 3, "d") == ""


def test_a_part_moving_against_its_port_is_refused_in_one_line(solid_member, tmp_path,
                                                                monkeypatch, capsys):
    """The solid member with its output spring spread over 4 mm about the port (the member's
    corner held back over that patch) moves its port against the port's direction (Δ
    -1.39e-6 m, measured): its Δ/SE is negative, and the refinement of a mechanism says so in
    one line, exit code 2, before any step."""
    import dataclasses

    from pacto_ng.post import refine_setup

    def spread(setup):
        return tuple(dataclasses.replace(p, spread=0.004) for p in part_ports(setup))

    part_ports = refine_setup.part_ports
    monkeypatch.setattr(refine_setup, "part_ports", spread)
    run = tmp_path / "run"
    shutil.copytree(solid_member, run, ignore=shutil.ignore_patterns("refine"))
    code = main(["refine", str(run), "--steps", "1", "--quiet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1
    assert "Δ/SE is -" in err[0] and "against the port's direction" in err[0]
