"""Resources checked before they run out (issue 18, part 5; pacto_ng/resources.py): elements,
displacement dofs, memory and meshing time estimated from the mesh options and the order
before any mesh is made, refused with one line and exit code 2; and PACTO_THREADS refused
with one line naming it (pacto_ng/threads.py)."""
import os
import subprocess
import sys
import importlib
import time

import pytest

from pacto_ng import resources
from pacto_ng.cli import main
from pacto_ng.params import InputError

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


class MeshingStarted(Exception):
    pass


@pytest.fixture
def no_meshing(monkeypatch):
    """Meshing must not start: every mesh builder raises MeshingStarted."""
    from netgen import occ

    import pacto_ng.geometry_kinds as kinds

    def started(*args, **kwargs):
        raise MeshingStarted

    import pacto_ng.studies as studies

    monkeypatch.setattr(kinds, "structured_mesh", started)
    monkeypatch.setattr(kinds, "netgen_mesh", started)
    monkeypatch.setattr(kinds, "structured_box", started)  # a Box's hexahedra
    monkeypatch.setattr(kinds, "netgen_box_mesh", started)
    monkeypatch.setattr(studies, "structured_mesh", started)  # the C-beam analysis's mesher
    monkeypatch.setattr(studies, "netgen_mesh", started)
    monkeypatch.setattr(occ, "OCCGeometry", started)


def _refused(args, tmp_path, capsys) -> tuple[str, float]:
    """Run ``pacto ARGS`` in this process: exit code 2, one line on stderr; (line, seconds)."""
    argv = [*args, "--out", str(tmp_path / "out")]
    main(["run", "--no-part", "mbb", "--show-parameters"])
    importlib.import_module("pacto_ng.commands")  # imports done: the timing is the check's
    capsys.readouterr()
    t = time.perf_counter()
    code = main(argv)
    seconds = time.perf_counter() - t
    err = capsys.readouterr().err
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("pacto: error: "), err
    return lines[0], seconds


# -- the issue's three commands: refused fast, before meshing --------------------------------
@pytest.mark.parametrize("args, words", [
    # the issue's 74.5 GiB: nelx = nely = 100000 (a 1e10 array of region numbers)
    (["run", "--no-part", "pa-inverter", "--nelx", "100000", "--nely", "100000"],
     ("nelx x nely = 100000 x 100000", "quads", "memory", "mesh_time_limit")),
    (["run", "--no-part", "mbb", "--order", "3", "--nelx", "5000", "--nely", "5000"],
     ("order 3", "memory", "smaller nelx, nely or order")),
    (["run", "--no-part", "pa-inverter", "--maxh", "1e-5"],
     ("maxh = 1e-05", "triangles", "memory", "Netgen", "larger maxh")),
])
def test_refused_before_meshing(args, words, tmp_path, capsys, no_meshing):
    line, seconds = _refused(args, tmp_path, capsys)
    for w in words:
        assert w in line, line
    assert seconds < 1.0, f"{seconds:.2f} s: {line}"


@pytest.mark.parametrize("args, words", [
    (["run", "--no-part", "c-beam", "--maxh", "1e-6"],
     ("maxh = 1e-06", "triangles", "memory", "Netgen", "larger maxh")),
    (["run", "--no-part", "c-beam", "--nelx", "100000"],
     ("nelx = 100000 (100000 x 100000 quads)", "memory", "mesh_time_limit", "smaller nelx")),
])
def test_the_c_beam_analysis_is_refused_before_meshing(args, words, tmp_path, capsys,
                                                       no_meshing):
    """The C-beam analysis (its own mesher, an nelx x nelx grid or Netgen triangles on the
    10 m square) is checked like a run's mesh, before its folder is made."""
    line, seconds = _refused(args, tmp_path, capsys)
    for w in words:
        assert w in line, line
    assert seconds < 1.0, f"{seconds:.2f} s: {line}"
    assert not (tmp_path / "out").exists()


def test_the_c_beam_defaults_pass_the_check(tmp_path, no_meshing):
    with pytest.raises(MeshingStarted):
        main(["run", "--no-part", "c-beam", "--out", str(tmp_path / "out")])
    with pytest.raises(MeshingStarted):
        main(["run", "--no-part", "c-beam", "--maxh", "0.5", "--out", str(tmp_path / "trig")])


def test_order_3_grid_of_the_issue_refused_where_it_does_not_fit(tmp_path, capsys, no_meshing,
                                                                   monkeypatch):
    """mbb at order 3 on 400 x 300 (2.16e6 dofs; a whole run measured 6.9 GB peak here) is
    refused where less than its estimate is free (here: 4 GB), and passes the check here."""
    est = resources.estimate_grid((400, 300), 3, solver="sparsecholesky")
    assert est.dofs == 2 * (3 * 400 + 1) * (3 * 300 + 1)
    assert 6.0e9 < est.memory < 8.0e9  # measured 6.72 GB above the process's start
    monkeypatch.setattr(resources, "memory_limit", lambda: (4e9, "a 4 GB test limit"))
    line, seconds = _refused(["run", "--no-part", "mbb", "--order", "3", "--nelx", "400", "--nely", "300"],
                             tmp_path, capsys)
    assert "2,164,202 displacement dofs at order 3" in line and "4 GB" in line, line
    assert seconds < 1.0


def test_mesh_time_limit_is_the_override(tmp_path, capsys, no_meshing):
    """Beyond mesh_time_limit alone (memory fits): refused, and a larger mesh_time_limit lets
    the mesh be made (here: reaches the mesher)."""
    args = ["run", "--no-part", "pa-inverter", "--maxh", "0.0001"]  # ~4.6e6 triangles, ~15 min of Netgen
    line, _ = _refused(args, tmp_path, capsys)
    assert "Netgen" in line and "mesh_time_limit = 300 s" in line and "memory" not in line
    with pytest.raises(MeshingStarted):
        main([*args, "--set", "mesh_time_limit=3600", "--out", str(tmp_path / "out2")])


def test_every_case_passes_the_check(no_meshing):
    """Each built-in case at its defaults (its order for its model) reaches the mesher."""
    from pacto_ng.case import available_cases, mesh_for

    for case in available_cases():
        if case.analysis_only:
            continue
        with pytest.raises(MeshingStarted):
            mesh_for(case, case.resolve(case.defaults))


# -- the estimate against real meshes ---------------------------------------------------------
@pytest.mark.parametrize("name, scale", [("pa-inverter", 1.0), ("pneunet", 1.0),
                                         ("soft-finger", 1.0), ("jaw-gripper", 1.0)])
def test_estimate_against_real_meshes(name, scale):
    """Netgen triangles and dofs at orders 1-3 within a factor 1.15 of the real counts
    (measured 0.94-1.08 on the built-in cases' geometries: Layouts and netgen.occ shapes)."""
    from ngsolve import VectorH1

    from pacto_ng.case import get_case
    from pacto_ng.geometry import is_occ_shape
    from pacto_ng.meshing import mesh_geometry

    case = get_case(name)
    geo = case.make_geometry(case.defaults)
    h = case.defaults.maxh * scale
    tri = (resources.shape_elements(geo, h) if is_occ_shape(geo)
           else resources.netgen_elements(geo.width * geo.height, h, 2))
    mesh = mesh_geometry(geo, maxh=h).mesh
    for k in (1, 2, 3):
        est = resources.estimate_netgen(tri, k, 2)
        ndof = VectorH1(mesh, order=k).ndof
        assert 1 / 1.15 < est.elements / mesh.ne < 1.15, (k, est.elements, mesh.ne)
        assert 1 / 1.15 < est.dofs / ndof < 1.15, (k, est.dofs, ndof)


def test_grid_and_existing_mesh_counts_are_exact():
    from ngsolve import VectorH1

    from pacto_ng.mesh import Layout, netgen_mesh, structured_mesh

    quad = structured_mesh(Layout(2.0, 1.0), 12, 6)
    trig = netgen_mesh(Layout(2.0, 1.0), 0.2)
    for k in (1, 2, 3):
        assert resources.estimate_grid((12, 6), k).dofs == VectorH1(quad, order=k).ndof
        assert resources.estimate_mesh(quad, k).dofs == VectorH1(quad, order=k).ndof
        assert resources.estimate_mesh(trig, k).dofs == VectorH1(trig, order=k).ndof
        assert resources.estimate_mesh(trig, k).elements == trig.ne


def test_local_maxh_of_a_shape_counts():
    """A face's own maxh and an edge's smaller maxh raise the estimate (no meshing)."""
    from netgen import occ

    plain = occ.WorkPlane().Rectangle(1, 1).Face()
    base = resources.shape_elements(plain, 0.05)
    assert base == pytest.approx(resources.netgen_elements(1.0, 0.05, 2))
    fine_face = occ.WorkPlane().Rectangle(1, 1).Face()
    fine_face.maxh = 0.01
    assert resources.shape_elements(fine_face, 0.05) == pytest.approx(25 * base)
    fine_edge = occ.WorkPlane().Rectangle(1, 1).Face()
    fine_edge.edges.Min(occ.X).maxh = 0.005
    assert resources.shape_elements(fine_edge, 0.05) == pytest.approx(base + 6 * 1 / 0.005)


def test_occ_shape_refused_before_netgen(no_meshing):
    from netgen import occ

    from pacto_ng.meshing import mesh_geometry

    face = occ.WorkPlane().Rectangle(1, 1).Face()
    face.name = "design"
    with pytest.raises(InputError, match=r"maxh = 0\.0001: about 2\.3e\+08 triangles"):
        mesh_geometry(face, maxh=1e-4)


def test_mesh_file_checked_after_reading(tmp_path, monkeypatch):
    from pacto_ng.meshing import mesh_geometry
    from pacto_ng.mesh import Layout, netgen_mesh

    path = tmp_path / "part.vol"
    netgen_mesh(Layout(2.0, 1.0), 0.1).ngmesh.Save(str(path))
    assert mesh_geometry(str(path), maxh=1.0, order=3).mesh.ne > 0
    monkeypatch.setattr(resources, "memory_limit", lambda: (1e6, "a 1 MB test limit"))
    with pytest.raises(InputError, match=r"mesh file '.*part\.vol': \d+ triangles, [\d,]+ "
                                         r"displacement dofs at order 3; a run needs"):
        mesh_geometry(str(path), maxh=1.0, order=3)


def test_memory_limit_is_below_the_machine():
    limit, what = resources.memory_limit()
    phys = os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    assert 0 < limit <= resources._SAFETY * phys
    assert "%" in what


def test_refusal_line_names_what_to_change():
    est = resources.estimate_grid((100000, 100000), 1)
    with pytest.raises(InputError) as err:
        resources.check(est, "nelx x nely = 100000 x 100000", limit=(1e10, "10 GB"),
                        advice="give a smaller nelx")
    msg = str(err.value)
    assert "\n" not in msg and "10 GB" in msg and msg.endswith("give a smaller nelx")


# -- PACTO_THREADS ----------------------------------------------------------------------------
@pytest.mark.parametrize("value", ["64", "99999999999999999999"])
def test_too_many_threads_one_line_exit_2(value, tmp_path):
    """In a fresh process (NGSolve's thread count is process-wide)."""
    env = {**os.environ, "PACTO_THREADS": value}
    out = subprocess.run([sys.executable, "-m", "pacto_ng.cli", "run", "mbb", "--out",
                          str(tmp_path / "out"), "--set", "iterations=2"], cwd=REPO, env=env,
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 2, out.stderr
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and "PACTO_THREADS" in lines[0] and "cores" in lines[0], out.stderr
    assert "Traceback" not in out.stderr


@pytest.mark.parametrize("value", ["0", "-1", "two", "1.5"])
def test_bad_thread_counts_one_line_exit_2(value, tmp_path, capsys, monkeypatch):
    """Refused before NGSolve's thread count is set (so in this process)."""
    monkeypatch.setenv("PACTO_THREADS", value)
    assert main(["run", "--no-part", "mbb", "--out", str(tmp_path / "out"), "--set", "iterations=2"]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and "PACTO_THREADS" in lines[0]


def test_thread_count_within_the_cores(monkeypatch):
    from pacto_ng.threads import core_count, thread_count

    monkeypatch.setenv("PACTO_THREADS", str(core_count()))
    assert thread_count() == core_count()
    monkeypatch.setenv("PACTO_THREADS", str(core_count() + 1))
    with pytest.raises(InputError, match="PACTO_THREADS"):
        thread_count()
