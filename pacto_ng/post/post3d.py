"""``pacto export`` and ``pacto analyse`` of a 3D run (docs/postprocessing.md, "3D runs").

``export DIR --format stl`` writes the part of :mod:`.part3d` (the closed, smoothed surface of
{ρ̄ >= threshold}, pieces off the clamp dropped) as binary STL; ``--format vtk`` or ``vtu`` the
clipped tetrahedral solid (not smoothed) with the run's final state on it (:func:`part_solid`:
ρ̄, u, p, the model's strain and stress).  With ``mirror`` (the default) a case solved on a
half or a quarter is written whole, reflected about its symmetry planes (:mod:`.mirror3d`).
``analyse DIR`` remeshes that surface (the half or quarter as solved)
with Netgen tetrahedra (:func:`~.reanalysis3d.remesh_part`: the case's face names carried over
by position, the wetted faces named ``pressure``) and sweeps the pressures with the
Neo-Hookean ``fixed`` and ``follower`` analyses of :class:`~.reanalysis3d.Reanalysis3D`,
beside the expected Δ (the density design with the optimisation's own model, as in 2D).  It
writes ``DIR/analysis/``: ``analysis.json``, ``analysis.png``, ``design.stl``, ``part.vtu``
(the clipped solid) and ``remeshed.vtu`` (the tetrahedra with ``u`` of the follower state).

A two-material design (mm-gripper's chain in 3D): the part is that of the total solid ρ̄1,
as for one material (the STL is the whole part); its clipped solid is cut at the iso-surface
of the nodal ρ̄2 (smoothed to the vertices as ρ̄1 is) at ``threshold2`` (default 0.5), the
rule of the 2D part (:mod:`.materials`): ``stiff`` (E2) where ρ̄2 >= threshold2, ``soft`` (E1)
elsewhere (:func:`split_materials`), so that ``--format vtk|vtu`` carries each cell's material
and modulus.  ``analyse`` gives each remeshed tetrahedron the material of the nodal ρ̄2 at its
centroid (:func:`stiff_sampler`; the interface a staircase of tetrahedron faces, the 2D
part's element-wise mode) and analyses each with its modulus; analysis.json's ``materials``
holds each material's volume in the remesh and in the part cut at the iso-surface.

Not in 3D yet, refused in one line (exit code 2): the ``darcy`` analysis (skipped with a note
when other kinds are asked too), ``--threshold volume``, ``--format msh``, and output ports
on named points or edges (the 3D cases read their output on faces).
"""
from __future__ import annotations

import json
import time

import numpy as np

from ..files import atomic_path, atomic_write_text
from ..params import InputError
from ..threads import compute

EXPORT_FORMATS_3D = ("stl", "vtk", "vtu")


def is_3d(run) -> bool:
    """Whether a run folder's summary records a 3D mesh."""
    mesh = run.summary.get("mesh")
    return isinstance(mesh, dict) and mesh.get("dim") == 3


def _say(quiet, msg):
    if not quiet:
        print(msg, flush=True)


def _not_yet(what: str):
    return InputError(f"{what} is not supported for 3D runs yet")


def part_of_run_3d(run, threshold_value: float, threshold2: float = 0.5):
    """``(part, problem, setup, exclude)``: the :class:`~.part3d.Part3D` of a 3D run's final
    design at ``threshold_value``; InputError when there is none.  A two-material design: the
    part of ρ̄1, its solid cut into the materials at ρ̄2 = ``threshold2``
    (:func:`split_materials`)."""
    from .part3d import part3d, void_regions
    from .runs import design_density, rebuild

    setup = run.case.make_setup(run.params)
    with compute():
        problem = rebuild(run)
    exclude = void_regions(problem.mesh, setup)
    two = setup.materials == 2
    try:
        part = part3d(problem.mesh, design_density(problem), threshold_value,
                      clamp=setup.supports.clamp, exclude=exclude,
                      fields={RHO2: problem.values["rho_bar2"]} if two else None)
        if two:
            part.solid = split_materials(part.solid, threshold2)
    except ValueError as err:
        raise InputError(str(err)) from None
    return part, problem, setup, exclude


#: the point data of a two-material part's solid that holds the nodal ρ̄2
RHO2 = "rho2"


def split_materials(solid, threshold2: float):
    """A two-material part's clipped solid (point data :data:`RHO2`, the nodal ρ̄2) cut at the
    iso-surface ρ̄2 = ``threshold2`` (linear along the cells' edges, as the part is cut at ρ̄1):
    the cells where ρ̄2 >= ``threshold2`` get cell data ``material`` 2 (``stiff``, E2), the
    others 1 (``soft``, E1), the numbers of the sorted names as in the 2D part's VTU.  The
    volume is kept (the two pieces fill the solid); the points on the cut are merged."""
    from .materials import MATERIALS, SOFT, STIFF

    if not 0.0 < float(threshold2) < 1.0:
        raise ValueError(f"threshold2 must lie in (0, 1), got {threshold2!r}")
    solid = solid.copy()
    r2 = np.asarray(solid.point_data[RHO2], dtype=float).copy()
    # a vertex exactly at the threshold counts as stiff (moved 1e-9 above it), as part3d's ρ̄1
    r2[np.abs(r2 - threshold2) < 1e-9] += 1e-9
    solid.point_data[RHO2] = r2
    number = {name: i + 1 for i, name in enumerate(MATERIALS)}
    pieces = []
    for name, invert in ((SOFT, True), (STIFF, False)):  # invert: the cells below the value
        piece = solid.clip_scalar(scalars=RHO2, value=float(threshold2), invert=invert)
        if piece.n_cells:
            piece.cell_data["material"] = np.full(piece.n_cells, number[name], dtype=np.int64)
            pieces.append(piece)
    if not pieces:
        raise ValueError("the part's solid has no cells")
    return pieces[0] if len(pieces) == 1 else pieces[0].merge(pieces[1], merge_points=True)


def material_volumes(solid) -> dict:
    """``{material: m³}`` of a solid of :func:`split_materials` (every material, 0 when it has
    no cell)."""
    from .grid import cell_volumes
    from .materials import MATERIALS

    vol = cell_volumes(solid)
    mat = np.asarray(solid.cell_data["material"])
    return {name: float(vol[mat == i + 1].sum()) for i, name in enumerate(MATERIALS)}


def part_solid(part, problem=None):
    """The part's clipped solid (tetrahedra and wedges of the source mesh, not smoothed) with
    point data ``rho`` (the nodal ρ̄ it is clipped at) and, given the run's ``problem``
    (rebuilt and analysed: :func:`part_of_run_3d`), the run's final state on it, in SI units:

    * cell data ``rho_bar`` (``rho_bar1``, ``rho_bar2`` for two materials): ρ̄ of the
      optimisation element the cell was clipped from;
    * two materials (a solid of :func:`split_materials`): point data ``rho2`` (the nodal ρ̄2),
      cell data ``material`` (1 ``soft``, 2 ``stiff``), ``material_soft``,
      ``material_stiff`` (1 in that material's cells, else 0) and, given the ``problem``,
      ``E`` (Pa: E1 or E2);
    * point data ``p`` (Pa, pressure cases) and ``u`` (m): the run's Darcy pressure and
      displacement at the points;
    * cell data of the run model's strain and stress measures
      (:func:`~pacto_ng.outputs.strain_stress_measures`: ``strain`` and ``stress`` (σ) for a
      linear run, Green–Lagrange ``E_GL`` and second Piola–Kirchhoff ``S`` for the
      hyperelastic ones, ``E_W1``, ``E_W2``, ``S`` for Wang): the element means of the source
      element (design.vtu's values), each a symmetric tensor of 6 components in VTK's order xx,
      yy, zz, xy, yz, xz.

    Returns ``(solid, notes)``.  A run that stopped on a Newton failure has no equilibrium at
    its load: ρ̄ and p only, and ``notes`` says so.  ValueError when a point of the part is not
    found in the run's mesh or a field is not finite."""
    from ngsolve import GridFunction

    from ..outputs import strain_stress_measures, tensor_components

    from .materials import MATERIALS

    solid = part.solid.copy()
    cid = np.asarray(solid.cell_data["cid"])
    material = solid.cell_data.get("material")
    material = None if material is None else np.asarray(material)
    for name in [n for n in solid.point_data if n not in ("rho", RHO2)]:
        del solid.point_data[name]
    solid.clear_cell_data()
    if material is not None:
        solid.cell_data["material"] = material
        for i, name in enumerate(MATERIALS):
            solid.cell_data[f"material_{name}"] = (material == i + 1).astype(np.int64)
    if problem is None:
        return solid, []
    mesh, vals = problem.mesh, problem.values
    if material is not None:
        moduli = np.array([problem.params.E1, problem.params.E2], dtype=float)
        solid.cell_data["E"] = moduli[material - 1]
    for key in ("rho_bar", "rho_bar1", "rho_bar2"):
        if key in vals:
            solid.cell_data[key] = np.asarray(vals[key], dtype=float)[cid]
    pts = np.asarray(solid.points, dtype=float)
    mips = mesh(pts[:, 0].copy(), pts[:, 1].copy(), pts[:, 2].copy())
    if np.any(mips["nr"] < 0):
        raise ValueError(f"{int(np.sum(mips['nr'] < 0))} points of the part lie outside the "
                         f"run's mesh: its fields cannot be sampled there")
    if "p" in vals and problem.pressure_block is not None:
        solid.point_data["p"] = np.asarray(problem.pressure_block.gfp(mips)).ravel()
    notes = []
    if problem.failure:
        notes.append("no displacement, strain or stress: the run's own model has no "
                     f"equilibrium on its final design at the full load ({problem.failure})")
    else:
        solid.point_data["u"] = np.asarray(problem.mech.gfu(mips)).reshape(-1, 3)
        for name, cf in strain_stress_measures(problem).items():
            T = np.empty((mesh.ne, 6))
            for k, ((i, j), _) in enumerate(tensor_components(3)):
                gf = GridFunction(problem.mech.l2)
                gf.Set(cf[i, j])  # element mean (P0 projection), as design.vtu
                T[:, k] = gf.vec.FV().NumPy()
            solid.cell_data[name] = T[cid]
    for key, val in [*solid.point_data.items(), *solid.cell_data.items()]:
        if not np.all(np.isfinite(val)):
            raise ValueError(f"the field {key} on the part has non-finite values")
    return solid, notes


def write_part_solid(path, solid, scale: float = 1.0) -> None:
    """A solid of :func:`part_solid` as VTU or legacy VTK (by the extension of ``path``),
    coordinates and ``u`` times ``scale``."""
    solid = solid.copy()
    solid.points = np.asarray(solid.points, dtype=float) * scale
    if "u" in solid.point_data:
        solid.point_data["u"] = np.asarray(solid.point_data["u"]) * scale
    with atomic_path(path) as tmp:
        solid.save(str(tmp), binary=True)


def _plural(n: int, word: str) -> str:
    return f"{n} {word}" + ("" if n == 1 else "s")


def export_run_3d(run, fmt: str, *, out=None, threshold_value=None, quiet=False,
                  units: str = "m", mirror: bool = True, threshold2=None) -> int:
    """``pacto export`` of a 3D run: stl (the closed, smoothed part) or vtk / vtu (the clipped
    solid with the run's final state: :func:`part_solid`), at ``threshold_value``, else the
    analysis's (``DIR/analysis/analysis.json``), else 0.5; coordinates (and u) in ``units`` (m
    or mm).  ``mirror``: the part reflected about the mesh's symmetry planes
    (:func:`~.mirror3d.symmetry_planes`), whole; else the half or quarter as solved.  A
    two-material design: the STL is the whole part, the VTK/VTU has each cell's material and
    modulus, ρ̄2 thresholded at ``threshold2`` (default 0.5; :func:`split_materials`)."""
    from .export import UNITS
    from .mirror3d import is_symmetry_name, mirror_solid, mirror_surface, symmetry_planes
    from .part3d import closed_checks, write_part_stl
    from .runs import export_destination

    if fmt not in EXPORT_FORMATS_3D:
        raise _not_yet(f"--format {fmt}")
    prev = run.path / "analysis" / "analysis.json"
    if threshold_value is None and prev.exists():
        try:
            threshold_value = float(json.loads(prev.read_text())["settings"]["threshold"])
        except (ValueError, KeyError, TypeError):
            threshold_value = None
    threshold2 = 0.5 if threshold2 is None else float(threshold2)
    part, problem, setup, _ = part_of_run_3d(
        run, 0.5 if threshold_value is None else threshold_value, threshold2)
    planes = symmetry_planes(problem.mesh) if mirror else []
    surface = mirror_surface(part.surface, planes) if planes else part.surface
    whole = f"mirrored about {_plural(len(planes), 'plane')}"
    dst = export_destination(run, out, fmt)
    notes = []
    if fmt == "stl":
        write_part_stl(dst, surface, units, header=f"pacto_ng {run.case.name} part (3D)"
                       + (f", whole ({whole})" if planes else ""))
    else:
        try:
            solid, notes = part_solid(part, problem)
        except ValueError as err:
            raise InputError(f"export: {err}") from None
        write_part_solid(dst, mirror_solid(solid, planes), 1.0 / UNITS[units])
        notes.append("fields " + ", ".join([*solid.point_data, *solid.cell_data])
                     + " of the run's final state")
    if planes:
        notes.insert(0, f"whole: {whole} ({', '.join(map(str, planes))}), volume "
                        f"{surface.volume:.6g} m³")
    elif not mirror and any(map(is_symmetry_name, problem.mesh.GetBoundaries())):
        notes.insert(0, "the part as solved (--no-mirror)")
    if setup.materials == 2:
        vols = material_volumes(part.solid)
        notes.append("materials " + ", ".join(f"{k} {v:.6g} m³" for k, v in vols.items())
                     + f" as solved (ρ̄2 at {threshold2:g})")
    chk = closed_checks(surface)
    _say(quiet, f"{dst}: {run.case.name} part (3D), threshold {part.threshold:g}, volume "
                f"{part.volume:.6g} m³ as solved (thresholded, kept pieces "
                f"{part.volume_kept:.6g}: {100 * part.volume_error:+.2f} %; {part.dropped} of "
                f"{part.pieces} pieces off the clamp dropped), {surface.n_cells} triangles, "
                f"{chk['n_open_edges']} open edges, manifold {chk['manifold']}; units {units}"
                + "".join(f"; {n}" for n in notes))
    return 0


def _remeshed_vtu(path, mesh, gfu, E=None) -> None:
    """The part's tetrahedra with point data ``u`` (at the vertices); for a part of several
    materials (``E`` a dict ``{material: E}``) cell data ``material`` (1 ``soft``, 2 ``stiff``)
    and ``E``."""
    import meshio

    pts = np.asarray(mesh.ngmesh.Coordinates(), dtype=float)
    els = mesh.ngmesh.Elements3D().NumPy()
    tets = np.asarray(els["nodes"], dtype=np.int64)[:, :4] - 1
    u = np.asarray(gfu(mesh(pts[:, 0].copy(), pts[:, 1].copy(), pts[:, 2].copy())))
    cells = {}
    if isinstance(E, dict):
        from .materials import MATERIALS

        names = np.array(mesh.GetMaterials(), dtype=object)[np.asarray(els["index"]) - 1]
        cells = {"material": [np.array([MATERIALS.index(n) + 1 for n in names])],
                 "E": [np.array([E[n] for n in names], dtype=float)]}
    m = meshio.Mesh(pts, [("tetra", tets)], point_data={"u": u.reshape(-1, 3)},
                    cell_data=cells)
    with atomic_path(path) as tmp:
        m.write(str(tmp), file_format="vtu")


def stiff_sampler(solid, threshold2: float):
    """A two-material part's rule for the remesh (:func:`~.reanalysis3d.remesh_part`'s
    ``stiff_at``): points -> whether the nodal ρ̄2, interpolated linearly in the clipped
    ``solid`` (point data :data:`RHO2`), reaches ``threshold2``; a point outside the solid
    (the smoothed surface runs up to a fraction of an element outside the clipped one) takes
    the value at the solid's nearest vertex."""
    import pyvista as pv
    from scipy.spatial import cKDTree

    r2 = np.asarray(solid.point_data[RHO2], dtype=float)
    tree = cKDTree(np.asarray(solid.points, dtype=float))

    def stiff_at(points):
        points = np.asarray(points, dtype=float)
        probe = pv.PolyData(points).sample(solid)
        val = np.asarray(probe.point_data[RHO2], dtype=float).copy()
        out = ~np.asarray(probe.point_data["vtkValidPointMask"], dtype=bool)
        if out.any():
            val[out] = r2[tree.query(points[out])[1]]
        return val >= threshold2

    return stiff_at


def analyse_run_3d(run, *, pressures, threshold_value, maxh, order, kinds, threshold2=0.5,
                   quiet=False) -> int:
    """``pacto analyse`` of a 3D run (see the module docstring).  A two-material design:
    the remeshed part's tetrahedra are soft (E1) or stiff (E2) by the nodal ρ̄2 at their
    centroids (:func:`stiff_sampler`, ``threshold2``).  Returns the exit code (0)."""
    from .cli_commands import case_ports, default_pressures, expected_sweep
    from .export import plot_sweeps
    from .materials import MATERIALS, SOFT, STIFF, material_areas
    from .part3d import closed_checks, write_part_stl
    from .reanalysis3d import PRESSURE, Reanalysis3D, remesh_part
    from .report import _jsonable, _present
    from .runs import copy_gridfunction

    if threshold_value == "volume":
        raise _not_yet("--threshold volume")
    kinds3 = tuple(k for k in kinds if k != "darcy")
    if not kinds3:
        raise _not_yet("the darcy analysis")
    setup = run.case.make_setup(run.params)
    two = setup.materials == 2
    if setup.pressure is None:
        raise InputError(f"analyse: case '{run.case.name}' has no pressure load; the re-analysis "
                         f"applies to pressure cases only ('pacto export {run.path}' writes its "
                         f"part)")
    t0 = time.perf_counter()
    part, problem, setup, exclude = part_of_run_3d(run, threshold_value, threshold2)
    faces = set(problem.mesh.GetBoundaries())
    if any(port.region not in faces for port in setup.ports):
        raise _not_yet("an output port on a named point or edge")
    ports = case_ports(setup)
    pressures = default_pressures(run.load) if pressures is None else list(pressures)
    _say(quiet, f"analyse {run.path}: {run.case.name} (3D), model {run.params.model}, load "
                f"{run.load:g} Pa" + ("; darcy is not in 3D yet: skipped"
                                      if kinds3 != tuple(kinds) else ""))
    h = float(problem.h)
    maxh = 0.5 * h if maxh is None else float(maxh)
    try:
        rm = remesh_part(part.surface, problem.mesh, maxh, h, clamp=setup.supports.clamp,
                         exclude=exclude, wet_boundaries=setup.pressure.inlet,
                         pressure=copy_gridfunction(problem.pressure_block.gfp),
                         p_in=run.load, timeout=run.params.mesh_time_limit,
                         stiff_at=stiff_sampler(part.solid, threshold2) if two else None)
    except ValueError as err:
        raise InputError(f"analyse: {err}") from None
    if PRESSURE not in rm.areas:
        raise InputError(f"analyse: no face of the part is wetted (threshold "
                         f"{part.threshold:g}): it borders neither the inlet nor the "
                         f"pressurised region of the run's Darcy field")
    missing = [p.region for p in ports if p.region not in rm.areas]
    if missing:
        raise InputError(f"analyse: the part does not reach the output face '{missing[0]}' "
                         f"(threshold {part.threshold:g})")
    expected = expected_sweep(problem, run.x, pressures, run.load)
    supports = _present(setup.supports, rm.mesh)
    _say(quiet, f"  part: volume {part.volume:.4g} m³ ({100 * part.volume_error:+.2f} % of the "
                f"thresholded), remeshed {rm.mesh.ne} tetrahedra (maxh {maxh:g}; {rm.dropped} "
                f"off the clamp dropped), wetted area {rm.areas[PRESSURE]:.4g} m²; sweeps "
                f"{', '.join(kinds3)} at {len(pressures)} pressures")
    E = run.params.E1
    materials = None
    if two:
        E = {SOFT: run.params.E1, STIFF: run.params.E2}
        materials = dict(mode=rm.materials, threshold2=threshold2, E=E,
                         remeshed=material_areas(rm.mesh), part=material_volumes(part.solid))
        _say(quiet, "  materials (remeshed, " + rm.materials + " by ρ̄2 at the centroids; the "
                    "part cut at the iso-surface): " + ", ".join(
                        f"{k} {materials['remeshed'].get(k, 0.0):.4g} m³ "
                        f"({materials['part'][k]:.4g})" for k in MATERIALS))
    newton = run.params.newton.settings()
    sweeps = {}
    for kind in kinds3:
        ana = Reanalysis3D(rm.mesh, kind, E=E, nu=run.params.nu, supports=supports,
                           output=ports, order=order, newton=newton)
        sweeps[kind] = ana.sweep(pressures)
    out_dir = run.path / "analysis"
    out_dir.mkdir(parents=True, exist_ok=True)
    write_part_stl(out_dir / "design.stl", part.surface)
    write_part_solid(out_dir / "part.vtu", part_solid(part)[0])
    shown = next((sweeps[k] for k in ("follower", "fixed") if k in sweeps
                  and sweeps[k].converged.any()), None)
    if shown is not None:
        _remeshed_vtu(out_dir / "remeshed.vtu", rm.mesh, shown.displacement(), E)
    rows = []
    for i, P in enumerate(pressures):
        row = dict(pressure=P, expected=expected[i]["delta"])
        for kind, sw in sweeps.items():
            row[kind] = _jsonable({k: v for k, v in sw.table()[i].items() if k != "kind"})
        rows.append(row)
    data = dict(
        run=dict(case=run.case.name, model=run.params.model, load=run.load, design=run.design,
                 dim=3),
        settings=dict(threshold=part.threshold, maxh=maxh, order=order, kinds=list(kinds3),
                      E=E, nu=run.params.nu, supports={
                          k: list(v) for k, v in supports.__dict__.items()},
                      void=list(exclude)),
        volumes=dict(thresholded=part.volume_thresholded, kept=part.volume_kept,
                     surface=part.volume, surface_vs_kept=part.volume_error,
                     remeshed=rm.volume, pieces=part.pieces, dropped=part.dropped,
                     **closed_checks(part.surface)),
        remesh=dict(tetrahedra=rm.mesh.ne, dropped_tetrahedra=rm.dropped, areas=rm.areas,
                    wetted_area=rm.areas[PRESSURE]),
        pressures=rows, wall_time_s=time.perf_counter() - t0)
    if materials is not None:
        data["materials"] = materials
    if {"fixed", "follower"} <= set(sweeps):
        d = [(r["follower"]["delta"], r["fixed"]["delta"]) for r in rows]
        data["follower_vs_fixed"] = [None if a is None or b is None else (a - b) / abs(b)
                                     for a, b in d]
    atomic_write_text(out_dir / "analysis.json", json.dumps(data, indent=1))
    ok_exp = [r for r in expected if r["converged"]]
    plot_sweeps(out_dir / "analysis.png", list(sweeps.values()),
                expected=([r["pressure"] for r in ok_exp], [r["delta"] for r in ok_exp])
                if ok_exp else None, log=True,
                title=f"{run.case.name} — {run.params.model} design, 3D part")
    for r in rows:
        _say(quiet, f"  P = {r['pressure']:.3g} Pa: expected {r['expected']}, " + ", ".join(
            f"{k} {r[k]['delta']}" for k in sweeps))
    _say(quiet, f"  written to {out_dir} ({data['wall_time_s']:.1f} s)")
    return 0
