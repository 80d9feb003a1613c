"""The chain on an MPI-distributed mesh equals the serial chain (pacto_ng.parallel).

Runs ``mpirun`` on tests/parallel/mpi_chain.py; skipped where mpi4py or mpirun is missing
(README: the ``mpi`` extra and the system's MPI)."""
import csv
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import meshio
import numpy as np
import pytest
from scipy.spatial import cKDTree

from pacto_ng.case import build_problem, get_case

pytest.importorskip("mpi4py")
MPIRUN = shutil.which("mpirun")
pytestmark = pytest.mark.skipif(MPIRUN is None, reason="no mpirun on this machine")
SCRIPT = Path(__file__).with_name("mpi_chain.py")


def mpirun(ranks, *args, code=0):
    """``python3 -m mpi4py ARGS`` on ``ranks`` ranks (an uncaught error stops them all); its
    exit code must be ``code``."""
    cmd = [MPIRUN, "-n", str(ranks), "--oversubscribe"]
    if os.geteuid() == 0:
        cmd.append("--allow-run-as-root")
    env = dict(os.environ, OMPI_MCA_mpi_yield_when_idle="1", PACTO_THREADS="1")
    done = subprocess.run(cmd + [sys.executable, "-m", "mpi4py", *map(str, args)],
                          capture_output=True, text=True, timeout=600, env=env)
    assert done.returncode == code, done.stdout[-2000:] + done.stderr[-4000:]
    return done


SLOW = pytest.mark.slow  # covered by default by the follower case's Darcy and Neo-Hookean
#: Newton's tolerance of both routes where they differ by default (the serial direct one
#: 1e-10, the distributed Krylov one 1e-6): the same equations solved alike; pneunet-3d's
#: Neo-Hookean chain at its random design differed by 4e-8 without it (its inlet wall)
SAME_NEWTON = {"model": "neohookean", "newton_rtol": 1e-10}


@pytest.mark.parametrize("name, values", [
    ("cantilever-3d", {"maxh": 0.06}),
    pytest.param("cantilever-3d", {"maxh": 0.06, **SAME_NEWTON}, marks=SLOW),
    pytest.param("pneunet-3d", {"maxh": 0.006}, marks=SLOW),
    pytest.param("pneunet-3d", {"maxh": 0.006, **SAME_NEWTON}, marks=SLOW),
    ("pneunet-3d", {"maxh": 0.006, "model": "neohookean", "load_type": "follower",
                    "solver": "iterative"}),
])
def test_distributed_chain_equals_serial(tmp_path, name, values):
    """Objective, volume constraint and their gradients at a random design: three ranks (two
    holding elements) against the serial chain, to 1e-10 relative."""
    case = get_case(name)
    params = case.parameters(values)
    serial = build_problem(case, params)
    x = np.random.default_rng(3).uniform(0.2, 1.0, serial.n_design * serial.n_design_fields)
    f0, f, df0, df = serial.evaluate(x)
    (tmp_path / "params.json").write_text(json.dumps(values))
    np.save(tmp_path / "x.npy", x)
    mpirun(3, SCRIPT, name, tmp_path / "params.json", tmp_path / "x.npy", tmp_path / "out.npz")
    got = np.load(tmp_path / "out.npz")
    assert got["f0"] == pytest.approx(f0, rel=1e-10)
    assert np.allclose(got["f"], f, rtol=1e-10, atol=1e-12)
    assert np.abs(got["df0"] - df0).max() <= 1e-10 * np.abs(df0).max()
    for g, ref in zip(got["df"], df):
        assert np.abs(g - ref).max() <= 1e-10 * np.abs(ref).max()


def pacto(ranks, *args):
    """``pacto ARGS`` serially (ranks 0) or under mpirun."""
    if ranks == 0:
        done = subprocess.run([sys.executable, "-m", "pacto_ng.cli", *map(str, args)],
                              capture_output=True, text=True, timeout=600,
                              env=dict(os.environ, PACTO_THREADS="1"))
        assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-4000:]
        return
    mpirun(ranks, "-m", "pacto_ng.cli", *args)


def objectives(folder):
    with open(folder / "history.csv") as fh:
        return np.array([float(r["objective"]) for r in csv.DictReader(fh)])


RUN = ("cantilever-3d", "--maxh", "0.06", "--quiet")


@pytest.mark.slow  # 20-40 s: the default suite stays under 10 minutes
def test_mpi_run_and_resume_across_rank_counts(tmp_path):
    """``mpirun -n 3 pacto run`` (two ranks holding elements) gives the serial run's objective
    history to 1e-8, and its design.vtu the serial run's displacement and element fields; a run of 3 iterations on 3 ranks resumed serially, and one of 3 serial
    iterations resumed on 3 ranks, end with the uninterrupted run's design."""
    serial, dist = tmp_path / "serial", tmp_path / "dist"
    pacto(0, "run", *RUN, "--iterations", "6", "--out", serial)
    pacto(3, "run", *RUN, "--iterations", "6", "--out", dist)
    ref = objectives(serial)
    assert len(ref) == 6
    assert np.allclose(objectives(dist), ref, rtol=1e-8, atol=0)
    summary = json.loads((dist / "summary.json").read_text())
    assert summary["mpi"]["ranks"] == 3 and sum(summary["mpi"]["elements_per_rank"]) == \
        summary["mesh"]["elements"]
    # design.vtu: ρ̄ per element and u at the vertices of the serial mesh, the serial run's
    got, ref_vtu = meshio.read(dist / "design.vtu"), meshio.read(serial / "design.vtu")
    dist_pts, at = cKDTree(ref_vtu.points).query(got.points)
    assert dist_pts.max() < 1e-12
    u_ref = ref_vtu.point_data["u"]
    assert np.abs(got.point_data["u"] - u_ref[at]).max() <= 1e-8 * np.abs(u_ref).max()
    assert len(got.cell_data["rho_bar"][0]) == summary["mesh"]["elements"]
    # the element fields (ρ̄, x, the strain and stress measures), the serial run's: its
    # design.vtu (NGSolve's VTKOutput at order 1) holds them at each cell's own points
    first = ref_vtu.cells[0].data[:, 0]
    assert len(first) == len(got.cells[0].data)
    names = sorted(got.cell_data)
    assert {"rho_bar", "x", "stress_xy", "strain_zz"} <= set(names)
    for name in names:
        want = np.ravel(ref_vtu.point_data[name][first])
        assert np.abs(np.ravel(got.cell_data[name][0]) - want).max() <= 1e-8 * np.abs(want).max()
    # the pictures, drawn by rank 0 on the serial mesh
    from matplotlib.image import imread

    for name in ("design.png", "convergence.png"):
        rgb = imread(dist / name)[..., :3]
        assert rgb.shape[0] > 200 and rgb.std() > 0.05, name  # a picture, not a blank
    x_ref = np.load(serial / "checkpoint.npz")["x"]
    for first, then, name in ((3, 0, "d2s"), (0, 3, "s2d")):
        out = tmp_path / name
        pacto(first, "run", *RUN, "--iterations", "3", "--out", out)
        pacto(then, "resume", out, "--iterations", "6")
        assert np.allclose(objectives(out), ref, rtol=1e-8, atol=0)
        assert np.allclose(np.load(out / "checkpoint.npz")["x"], x_ref, rtol=0, atol=1e-8)


def test_a_distributed_run_writes_the_serial_run_s_figures_and_pictures(tmp_path):
    """A 2D two-material pressure case on a symmetric half (mm-gripper) on 3 ranks writes what
    the serial run writes: every figure of summary.json (the leak, the analysis's, the
    leakage figure and the material fractions among them), and design.png (mirrored), pressure.png, materials.png and convergence.png,
    drawn by rank 0 on the serial mesh it meshed: the serial run's pictures."""
    from matplotlib.image import imread

    run = ("mm-gripper", "--maxh", "0.008", "--iterations", "2", "--quiet", "--no-part")
    serial, dist = tmp_path / "serial", tmp_path / "dist"
    pacto(0, "run", *run, "--out", serial)
    pacto(3, "run", *run, "--out", dist)
    ref, got = (json.loads((d / "summary.json").read_text()) for d in (serial, dist))
    assert got["mpi"]["ranks"] == 3 and set(got) == set(ref) | {"mpi"}
    for key in ("leak", "output_displacement", "compliance", "strain_energy"):
        assert got[key] == pytest.approx(ref[key], rel=1e-8) and ref[key] != 0, key
    assert got["leakage"] == pytest.approx(ref["leakage"], rel=1e-8, abs=1e-12)
    for key in ("elements_checked", "cavity_elements", "skin"):
        assert got["leakage_detail"][key] == ref["leakage_detail"][key], key
    assert ref["leakage_detail"]["cavity_elements"] > 0
    for key, value in ref["material_fractions"].items():
        assert got["material_fractions"][key] == pytest.approx(value, rel=1e-10), key
    for name in ("design.png", "pressure.png", "materials.png", "convergence.png"):
        want, have = imread(serial / name), imread(dist / name)
        assert have.shape == want.shape, name
        assert np.abs(have - want).mean() <= 1e-3, name
    half = imread(dist / "design.png")  # mirrored: the domain drawn 0.2 x 0.2 m, square
    assert abs(half.shape[0] - half.shape[1]) <= 0.1 * half.shape[0]


@pytest.mark.slow  # 20-40 s: the default suite stays under 10 minutes
def test_a_distributed_run_makes_the_serial_run_s_part(tmp_path):
    """``mpirun -n 3 pacto run`` of a pressure case makes its part as the serial run does: rank
    0 analyses the final design on the serial mesh and makes, checks and analyses the part
    (the part entry of summary.json the serial run's to 1e-8, part.stl and part.png)."""
    run = ("pneunet", "--maxh", "0.008", "--iterations", "40", "--no-refine", "--quiet")
    serial, dist = tmp_path / "serial", tmp_path / "dist"
    pacto(0, "run", *run, "--out", serial)
    pacto(3, "run", *run, "--out", dist)
    ref, got = (json.loads((d / "summary.json").read_text())["part"] for d in (serial, dist))
    assert ref["made"] and ref["analysed"] and set(got) == set(ref)
    for key in ("elements", "sealed", "kind", "order", "converged"):
        assert got[key] == ref[key], key
    for key in ("output_displacement", "output_displacement_design", "gap", "measure"):
        assert got[key] == pytest.approx(ref[key], rel=1e-8), key
    for name in ("part.stl", "part.png"):
        assert (dist / name).stat().st_size > 0, name


@pytest.mark.slow
def test_a_distributed_pressure_run_draws_its_pressure(tmp_path):
    """A 3D pressure case on 3 ranks: design.vtu holds p at the serial mesh's vertices, and
    rank 0 draws pressure.png with design.png (about 40 s)."""
    from matplotlib.image import imread

    out = tmp_path / "p"
    pacto(3, "run", "pneunet-3d", "--maxh", "0.007", "--iterations", "2", "--quiet", "--out",
          out)
    vtu = meshio.read(out / "design.vtu")
    p = np.ravel(vtu.point_data["p"])
    assert np.all(np.isfinite(p)) and p.max() == pytest.approx(1e5, rel=1e-6)
    for name in ("design.png", "pressure.png", "convergence.png"):
        rgb = imread(out / name)[..., :3]
        assert rgb.shape[0] > 200 and rgb.std() > 0.05, name


def test_mpi_nonlinear_run_chooses_its_load_ramp_as_the_serial_run(tmp_path):
    """A Neo-Hookean pneunet-3d run: the load ramp chosen from the first linear analysis (the
    99th percentile of the material's strain, here over both parts) and the objective history
    on 3 ranks equal the serial run's."""
    # Newton's tolerance set: by default each route has its own (the distributed run's Krylov
    # route 1e-6, the serial direct one 1e-10), and the comparison is of the same equations
    # without the inlet wall: the uniform start design's strain then asks for a ramp
    run = ("pneunet-3d", "--maxh", "0.006", "--model", "neohookean", "--iterations", "3",
           "--set", "newton_rtol=1e-10", "--set", "inlet_wall=0", "--quiet")
    serial, dist = tmp_path / "serial", tmp_path / "dist"
    pacto(0, "run", *run, "--out", serial)
    pacto(3, "run", *run, "--out", dist)
    ref = json.loads((serial / "summary.json").read_text())["load_ramp_choice"]
    got = json.loads((dist / "summary.json").read_text())["load_ramp_choice"]
    assert ref["chosen"] > 0 and got["chosen"] == ref["chosen"]
    assert got["strain_p99"] == pytest.approx(ref["strain_p99"], rel=1e-9)
    assert np.allclose(objectives(dist), objectives(serial), rtol=1e-8, atol=0)


def test_commands_of_one_process_are_refused_under_mpirun(tmp_path):
    """evaluate, export, check-gradients ... under mpirun: one line from rank 0, exit code 2,
    nothing written (each rank would run the command alone, into the same folder)."""
    out = tmp_path / "ev"
    done = mpirun(2, "-m", "pacto_ng.cli", "evaluate", *RUN, "--density",
                  tmp_path / "none.npz", "--out", out, code=2)
    errors = [ln for ln in done.stderr.splitlines() if ln.startswith("pacto:")]
    assert errors == ["pacto: error: evaluate: runs on one process, not under mpirun (only "
                      "'run' and 'resume' are distributed): start it as 'pacto evaluate ...' "
                      "without mpirun"]
    assert "Traceback" not in done.stderr and not out.exists()
