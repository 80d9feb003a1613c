"""``pacto evaluate``: one analysis of a given design (no optimisation)."""
from __future__ import annotations

import json
import os
import sys
import time
import zipfile
from pathlib import Path

import numpy as np

from .case import Case, build_problem
from .errors import InputError
from .files import RUN_FILES, atomic_write_text, claim_folder
from .outputs import one_mesh, summary_dict, write_vtu
from .params import Parameters
from .physics.equilibrium import NewtonFailure
from .problem import Problem
from .runner import prepare_output


def read_density(path: str, problem: Problem, *, filtered: bool = False) -> tuple[np.ndarray, bool]:
    """The design a file holds, and whether it is design variables (to be filtered and
    projected) rather than physical densities ρ̄.

    Formats (element order: NGSolve's, i.e. ``mesh.Elements()`` and the order of the cells of
    design.vtu):

    * ``.npy``, ``.csv``, ``.txt``: one value per element of the mesh, or for structured quads a
      nely x nelx grid whose row 0 is the top row of elements; ρ̄, or design variables with
      ``--filtered`` (passive elements' values are ignored then);
    * ``checkpoint.npz`` of a run: its design variables ``x`` (one per *design* element, two
      fields stacked for two materials), always filtered and projected, as the run did (with
      the penalty and β of the run's last iteration: :func:`checkpoint_schedule`);
    * ``design.vtu`` of a run: its element field ``rho_bar`` (``x`` with ``--filtered``).
    """
    p = problem.params
    fp = Path(path)
    if not fp.is_file():
        raise InputError(f"--density: file '{path}' does not exist")
    suffix = fp.suffix.lower()
    if suffix == ".npz":
        return _checkpoint_design(fp, problem), True
    try:
        if suffix == ".npy":
            arr = np.load(fp, allow_pickle=False)
        elif suffix in (".csv", ".txt"):
            if not fp.read_text().strip():
                raise InputError(f"--density: '{path}' is empty")
            arr = np.loadtxt(fp, delimiter="," if suffix == ".csv" else None, ndmin=1)
        elif suffix == ".vtu":
            arr = _vtu_element_field(fp, "x" if filtered else "rho_bar", problem.mesh.ne)
        else:
            raise InputError(f"--density: '{path}' must be a .npy, .csv, .txt, .vtu or a "
                             "checkpoint .npz file")
    except InputError:
        raise
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile) as err:  # unreadable
        raise InputError(f"--density: cannot read '{path}' ({type(err).__name__}: {err})") from None
    if not (np.issubdtype(arr.dtype, np.integer) or np.issubdtype(arr.dtype, np.floating)):
        raise InputError(f"--density: '{path}' holds {arr.dtype} values; expected real numbers")
    arr = np.asarray(arr, dtype=float)
    ne = problem.mesh.ne
    grid = p.nelx > 0 and arr.shape == (p.nely, p.nelx)
    vector = arr.ndim == 1 or (arr.ndim == 2 and 1 in arr.shape)
    if grid:
        arr = arr[::-1].ravel()  # row 0 is the top row of elements
    elif vector:
        arr = arr.ravel()
    elif arr.ndim == 2 and p.nelx > 0:
        raise InputError(f"--density: '{path}' is a {arr.shape[0]} x {arr.shape[1]} grid, "
                         f"the mesh is nely x nelx = {p.nely} x {p.nelx}")
    else:
        raise InputError(f"--density: '{path}' is an array of shape {arr.shape}; expected one "
                         "value per element" + (" or a nely x nelx grid" if p.nelx else ""))
    if arr.size != ne:
        raise InputError(f"--density: '{path}' holds {arr.size} values, the mesh has {ne} elements")
    if not np.all(np.isfinite(arr)) or arr.min() < 0 or arr.max() > 1:
        raise InputError(f"--density: values in '{path}' must be finite and lie in [0, 1]")
    if filtered:
        arr = arr[problem.field.design_index]
    else:
        field = problem.field
        changed = int(np.count_nonzero(arr[field.solid] != 1.0)
                      + np.count_nonzero(arr[field.void] != 0.0))
        if changed:
            print(f"evaluate: the values of {changed} passive elements in '{path}' replaced "
                  "by the case's (solid 1, void 0)", file=sys.stderr)
    return arr, filtered


def _checkpoint_design(fp: Path, problem: Problem) -> np.ndarray:
    try:
        with np.load(fp, allow_pickle=False) as data:
            x = np.asarray(data["x"], dtype=float).ravel()
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile) as err:
        raise InputError(f"--density: '{fp}' is not a readable checkpoint ({type(err).__name__}: "
                         f"{err})") from None
    n = problem.n_design * problem.n_design_fields
    if x.size != n:
        raise InputError(f"--density: checkpoint '{fp}' holds {x.size} design variables, this "
                         f"case and mesh have {n} (another case or mesh)")
    if not np.all(np.isfinite(x)) or x.min() < 0 or x.max() > 1:
        raise InputError(f"--density: design variables in '{fp}' must be finite, in [0, 1]")
    return x


def checkpoint_schedule(fp: str | os.PathLike, schedule) -> tuple[float, float]:
    """The penalty and β of the last iteration of the run a checkpoint was written by (the
    iteration ``k - 1`` of its count ``k``, whose β its history may decide)."""
    try:
        with np.load(fp, allow_pickle=False) as data:
            k = int(data["k"])
            history = json.loads(str(data["history"]))
        return schedule.values(max(k - 1, 0), history)[:2]
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile) as err:
        raise InputError(f"--density: '{fp}' is not a readable checkpoint ({type(err).__name__}: "
                         f"{err})") from None


def _vtu_element_field(fp: Path, name: str, ne: int) -> np.ndarray:
    """An element-constant field of a design.vtu: one value per element (NGSolve writes each
    element's corners as points of their own, and order >= 2 runs as 4 sub-cells each)."""
    import meshio

    m = meshio.read(fp)
    if name not in m.point_data:
        raise InputError(f"--density: '{fp}' has no field '{name}' (fields: "
                         f"{', '.join(m.point_data) or 'none'})")
    cells = np.concatenate([c.data for c in m.cells])
    vals = np.asarray(m.point_data[name], dtype=float).reshape(len(m.points), -1)[:, 0]
    per_cell = vals[cells[:, 0]]
    if per_cell.size % ne:
        raise InputError(f"--density: '{fp}' has {per_cell.size} cells, the mesh has {ne} "
                         "elements (another mesh)")
    return per_cell.reshape(ne, -1).mean(axis=1)


def evaluate_design(case: Case, params: Parameters, density: str, out, *, filtered: bool,
                    quiet: bool = False, overwrite: bool = False) -> int:
    """One analysis of a given design (no optimisation); writes summary.json and design.vtu.

    A folder holding a run or earlier results is refused (one-line InputError) unless
    ``overwrite``: then pacto's files in it are removed first."""
    path = prepare_output(out)
    src = Path(density)
    if overwrite and src.name in RUN_FILES and src.resolve().parent == path.resolve():
        raise InputError(f"evaluate --overwrite: --density '{density}' is one of the files it "
                         "would remove: choose another --out")
    with claim_folder(path, "evaluate", overwrite=overwrite):
        return _evaluate(case, params, density, path, filtered=filtered, quiet=quiet)


def _evaluate(case: Case, params: Parameters, density: str, path: Path, *, filtered: bool,
              quiet: bool) -> int:
    t0 = time.perf_counter()
    if not Path(density).is_file():  # before the problem is built
        raise InputError(f"--density: file '{density}' does not exist")
    problem = build_problem(case, params)
    arr, filtered = read_density(density, problem, filtered=filtered)
    if problem.n_design_fields != 1 and not Path(density).suffix.lower() == ".npz":
        raise InputError("evaluate: two-material cases need both fields: give the run's "
                         "checkpoint.npz")
    sched = params.schedule.schedule()
    if Path(density).suffix.lower() == ".npz":  # the run's own last penalty and β
        problem.apply_schedule(*checkpoint_schedule(density, sched), 1.0)
    else:
        problem.apply_schedule(*sched.final_values())
    x = None
    failure = None
    try:
        if filtered:
            x = arr
            problem.chain.forward(x=x)
        else:
            rho = arr.copy()
            rho[problem.field.solid] = 1.0
            rho[problem.field.void] = 0.0
            problem.chain.forward(rho_bar=rho)
    except NewtonFailure as err:  # written too: the load reached and why it stopped
        failure = err

    class _R:
        converged = failure is None
        stopped = "evaluated" if failure is None else "newton"
        message = "single analysis" if failure is None else str(failure)
        best = None

    summ = summary_dict(problem, [], _R, time.perf_counter() - t0, one_mesh(problem))
    summ["evaluated_from"] = str(density)
    summ["filtered"] = filtered
    write_vtu(path / "design", problem, x)
    atomic_write_text(path / "summary.json", json.dumps(summ, indent=1))  # last: complete
    if failure is not None:
        print(f"evaluate: no equilibrium at the full load: {failure} (summary.json records the "
              "load reached)", file=sys.stderr)
        return 1
    if not quiet:
        keys = ("objective", "compliance", "output_displacement", "strain_energy", "volume_fraction")
        print("  ".join(f"{k} {summ[k]:.6g}" for k in keys if summ[k] is not None))
    return 0
