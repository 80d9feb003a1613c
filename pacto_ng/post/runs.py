"""A finished run folder read back: its case, parameters, summary and final design
(:func:`load_run`), its problem rebuilt with that design analysed (:func:`rebuild`), and the
thresholded, remeshed part of it (:func:`part_of_run`)."""
from __future__ import annotations

import json
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .. import resources
from ..case import build_problem, read_run_params
from ..delta import output_displacement
from ..errors import InputError
from ..mesh import Meshed
from ..params import Parameters
from ..physics.equilibrium import NewtonFailure
from ..threads import compute
from .grid import cell_areas, element_materials, mesh_to_pyvista
from .materials import SOFT, STIFF, stiff_region
from .remesh import remesh
from .threshold import threshold


# ------------------------------------------------------------------------------------------
# a finished run
@dataclass
class Run:
    """A finished run folder: its case, parameters, summary and final design."""

    path: Path
    case: object
    params: Parameters
    summary: dict
    x: np.ndarray
    design: str  # "x" or "last_good"
    k: int  # optimisation iterations done
    history: list  # one row per iteration (the values the schedule gave it among them)

    @property
    def load(self) -> float:
        return float(self.params.load)


def load_run(folder, command: str, case=None) -> Run:
    """Read ``params.json``, ``summary.json`` and ``checkpoint.npz``; InputError if anything
    that a finished run holds is missing."""
    path = Path(folder)
    if not path.is_dir():
        raise InputError(f"{command}: '{folder}' is not a folder")
    info, case, params = read_run_params(path, command, case)
    if case.analysis_only:
        raise InputError(f"{command}: '{folder}' is an analysis case ({case.name}), not an "
                         f"optimised design")
    try:
        summary = json.loads((path / "summary.json").read_text())
        if not isinstance(summary, dict):
            raise ValueError("not an object")
    except (OSError, ValueError):
        raise InputError(f"{command}: '{folder}' holds no finished run (summary.json missing: "
                         f"still running, or stopped before its first result)") from None
    try:
        with np.load(path / "checkpoint.npz", allow_pickle=False) as data:
            use_last_good = summary.get("stopped") == "newton" and "last_good" in data.files
            design = "last_good" if use_last_good else "x"
            x = np.asarray(data[design], dtype=float).copy()
            k = int(data["k"])
            history = json.loads(str(data["history"]))
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile):
        raise InputError(f"{command}: '{folder}' has no readable checkpoint.npz (the final "
                         f"design)") from None
    return Run(path, case, params, summary, x, design, k, history)


def export_destination(run: Run, out, fmt: str) -> Path:
    """Where ``pacto export`` writes: ``out``, or ``DIR/export/design.FMT``; its folder made,
    an ``out`` of another suffix or a folder that cannot be made refused in one line."""
    dst = Path(out) if out else run.path / "export" / f"design.{fmt}"
    if dst.suffix.lower() != f".{fmt}":
        raise InputError(f"--out: '{dst}' must end in .{fmt}")
    try:
        dst.parent.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise InputError(f"--out: cannot create '{dst.parent}' ({err.strerror})") from None
    return dst


def rebuild(run: Run):
    """The run's problem with its final design analysed at the run's load (as ``run.py`` does
    for summary.json).  Returns the problem; ``problem.values`` hold ρ̄, p and Δ."""
    problem = build_problem(run.case, run.params)
    if run.x.size != problem.field.n * problem.n_design_fields:
        raise InputError(f"the design in '{run.path}' has {run.x.size} values, the rebuilt "
                         f"problem {problem.field.n * problem.n_design_fields} (mesh changed?)")
    problem.apply_schedule(*run.params.schedule.schedule().values(max(run.k - 1, 0),
                                                                  run.history))
    problem.failure = None
    try:
        problem.chain.forward(x=run.x)
    except NewtonFailure as err:
        # a run stopped by a Newton failure: ρ̄ and the Darcy field are computed before the
        # mechanics (the chain keeps its values as they fill); Δ at the full load is not
        problem.failure = str(err)
        if "rho_bar" not in problem.values and "rho_bar1" not in problem.values:
            raise InputError(f"the final design of '{run.path}' cannot be analysed ({err})") \
                from None
    return problem


def at_order(problem, order: int):
    """``problem``'s design analysed at displacement order ``order`` on the same elements, with
    the same penalty, β and load: a second problem of the same case (its chain run forward on
    ``problem``'s design variables), or ``problem`` itself when it has that order.  The part
    is analysed at order 2 while runs optimise at order 1, whose elements are stiffer: the
    design's figure the part is compared with must be of the part's order.  A robust run's
    second problem is of the standard chain: its design is the robust run's intermediate
    (blueprint) design, the one its Δ and its part are of, analysed once instead of with its
    eroded and dilated realisations.  Raises NewtonFailure when the design has no equilibrium
    at that order."""
    if int(problem.params.order) == int(order):
        return problem
    meshed = Meshed(problem.mesh, float(problem.h), problem.shape)
    twin = build_problem(problem.case, problem.params.replace(order=int(order), robust=0),
                         meshed=meshed)
    twin.apply_schedule(*problem.schedule_now())
    with compute():
        twin.chain.forward(x=problem.values["x"])
    return twin


def design_delta(problem) -> float | None:
    """The output displacement Δ of the design ``problem`` last analysed (None: no port)."""
    vals = problem.values
    return float(vals["delta"]) if "delta" in vals else output_displacement(problem)


def domain_of(problem, setup):
    """``(shape, exclude)``: the netgen.occ shape the problem's mesh was made from (None for a
    mesh file or structured quads) and, with a shape, the passive void faces to leave out of
    the thresholding (the part is built on the shape's own edges; see
    :func:`~pacto_ng.post.remesh.remesh`)."""
    shape = getattr(problem, "shape", None)
    if shape is None:
        return None, ()
    faces = {f.name for f in shape.faces}
    return shape, tuple(n for n in getattr(setup, "void", ()) if n in faces)


def thresholded_elements(th) -> np.ndarray:
    """Element ρ in {0, 1} of the thresholded design: 1 where at least half of the element's
    area lies inside the clipped solid of :func:`~pacto_ng.post.threshold.threshold` (0 in the
    materials it left out)."""
    grid = mesh_to_pyvista(th.source)
    grid.point_data["rho"] = th.nodal
    grid.cell_data["cid"] = np.arange(grid.n_cells)
    solid = grid.clip_scalar(scalars="rho", value=th.threshold, invert=False)
    inside = np.bincount(np.asarray(solid.cell_data["cid"]), weights=cell_areas(solid),
                         minlength=grid.n_cells)
    out = (inside >= 0.5 * cell_areas(grid)).astype(float)
    if th.excluded:
        out[np.isin(element_materials(th.source), list(th.excluded))] = 0.0
    return out


def copy_gridfunction(gf):
    from ngsolve import GridFunction

    out = GridFunction(gf.space)
    out.vec.data = gf.vec
    return out


def design_density(problem) -> np.ndarray:
    """ρ̄ of the design; for two materials the total solid ρ̄1."""
    vals = problem.values
    return np.asarray(vals["rho_bar"] if "rho_bar" in vals else vals["rho_bar1"], dtype=float)


def materials_of(problem, setup, params, threshold2: float, exclude=()):
    """``(stiff, E)`` of a run's part: one material, ``(None, E1)``; two materials, the stiff
    region of ρ̄2 thresholded at ``threshold2`` (:func:`~pacto_ng.post.materials.stiff_region`)
    and ``{"soft": E1, "stiff": E2}``."""
    if setup.materials == 1:
        return None, float(params.E1)
    rho2 = np.asarray(problem.values["rho_bar2"], dtype=float)
    return (stiff_region(problem.mesh, rho2, threshold2, exclude=exclude),
            {SOFT: float(params.E1), STIFF: float(params.E2)})


def check_part_mesh(run: Run, problem, rho: np.ndarray, maxh: float, *,
                    order: int | None = None, solver: str | None = None) -> None:
    """Refuse with one line (an InputError), before Netgen starts, a remesh of the run's part
    at ``maxh`` that would not fit this machine (:func:`pacto_ng.resources.estimate_part`):
    its triangles from the solid area of the design ``rho`` (``Σ a_e ρ̄_e``, about the
    thresholded part's), its meshing time against the run's ``mesh_time_limit`` and, with
    ``order``, the memory of a re-analysis on it (``solver``: its displacement system's)."""
    area = float(problem.field.areas @ rho)
    resources.check(resources.estimate_part(area, maxh, order, dim=problem.mesh.dim,
                                            solver=solver),
                    f"--maxh = {maxh:g}", mesh_time_limit=run.params.mesh_time_limit,
                    advice="give a larger --maxh" + (" or a lower --order" if order else ""),
                    longer="the run's setting")


def part_of_run(run: Run, threshold_value: float, maxh: float | None, threshold2: float = 0.5):
    """Threshold and remesh the final design of a run (the wetting rule for pressure cases;
    two materials: the regions ``soft`` and ``stiff``, ρ̄2 thresholded at ``threshold2``).
    Returns ``(Thresholded, Remeshed, problem)``; InputError when there is no part."""
    setup = run.case.make_setup(run.params)
    with compute():
        problem = rebuild(run)
    rho = design_density(problem)
    shape, exclude = domain_of(problem, setup)
    kw = {}
    if setup.pressure is not None and problem.pressure_block is not None:
        kw = dict(pressure=copy_gridfunction(problem.pressure_block.pressure), p_in=run.load,
                  wet_boundaries=setup.pressure.inlet)
    h = 0.5 * problem.h if maxh is None else maxh
    check_part_mesh(run, problem, rho, h)
    try:
        th = threshold(problem.mesh, rho, threshold_value, exclude=exclude)
        stiff, _ = materials_of(problem, setup, run.params, threshold2, exclude)
        rm = remesh(th, h, clamp=setup.supports.clamp, domain=shape, stiff=stiff, **kw)
    except ValueError as err:
        raise InputError(f"{err}") from None
    return th, rm, problem
