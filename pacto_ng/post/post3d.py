"""The 3D part's solid for ``pacto export`` and its two materials (docs/postprocessing.md, "3D
runs"; ``pacto export`` of a 3D run is :mod:`.cli_commands`'s, as of a 2D run, its 3D steps
in :mod:`.export_part`; ``pacto analyse`` of a 3D run is :mod:`.analyse`'s).

:func:`part_solid` gives the clipped tetrahedral solid of a :class:`~.part3d.Part3D` (not
smoothed) the run's final state (ρ̄, u, p, the model's strain and stress), which
:func:`write_part_solid` writes as VTK or VTU.

A two-material design (mm-gripper's chain in 3D): the part is that of the total solid ρ̄1,
as for one material (the STL is the whole part); its clipped solid is cut at the iso-surface
of the nodal ρ̄2 (smoothed to the vertices as ρ̄1 is) at ``threshold2`` (default 0.5), the
rule of the 2D part (:mod:`.materials`): ``stiff`` (E2) where ρ̄2 >= threshold2, ``soft`` (E1)
elsewhere (:func:`split_materials`), so that ``--format vtk|vtu`` carries each cell's material
and modulus.  The remeshed part (:func:`~.remesh3d.remesh_part`) gives each tetrahedron the
material of the nodal ρ̄2 at its centroid (:func:`stiff_sampler`; the interface a staircase
of tetrahedron faces, the 2D part's element-wise mode).
"""
from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ..files import atomic_path
from ..measures import strain_stress_measures, tensor_components
from .grid import cell_volumes
from .materials import MATERIALS, SOFT, STIFF


def is_3d(run) -> bool:
    """Whether a run folder's summary records a 3D mesh."""
    mesh = run.summary.get("mesh")
    return isinstance(mesh, dict) and mesh.get("dim") == 3


#: the point data of a two-material part's solid that holds the nodal ρ̄2
RHO2 = "rho2"


def split_materials(solid, threshold2: float):
    """A two-material part's clipped solid (point data :data:`RHO2`, the nodal ρ̄2) cut at the
    iso-surface ρ̄2 = ``threshold2`` (linear along the cells' edges, as the part is cut at ρ̄1):
    the cells where ρ̄2 >= ``threshold2`` get cell data ``material`` 2 (``stiff``, E2), the
    others 1 (``soft``, E1), the numbers of the sorted names as in the 2D part's VTU.  The
    volume is kept (the two pieces fill the solid); the points on the cut are merged."""
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
    vol = cell_volumes(solid)
    mat = np.asarray(solid.cell_data["material"])
    return {name: float(vol[mat == i + 1].sum()) for i, name in enumerate(MATERIALS)}


def solid_elements(solid, volumes) -> np.ndarray:
    """Element ρ in {0, 1} of a thresholded 3D design: 1 where at least half of the element's
    volume (``volumes``, one per source element) lies inside the clipped ``solid`` of
    :func:`~.part3d.part3d` (cell data ``cid``: the source element of each clipped cell), 0
    elsewhere (the 3D counterpart of :func:`~.runs.thresholded_elements`)."""
    volumes = np.asarray(volumes, dtype=float)
    inside = np.bincount(np.asarray(solid.cell_data["cid"]), weights=cell_volumes(solid),
                         minlength=len(volumes))
    return (inside >= 0.5 * volumes).astype(float)


def part_solid(part, problem=None):
    """The part's clipped solid (tetrahedra and wedges of the source mesh, not smoothed) with
    point data ``rho`` (the nodal ρ̄ it is clipped at) and, given the run's ``problem``
    (rebuilt and analysed: :func:`~.export_part.make_3d`), the run's final state on it, in SI units:

    * cell data ``rho_bar`` (``rho_bar1``, ``rho_bar2`` for two materials): ρ̄ of the
      optimisation element the cell was clipped from;
    * two materials (a solid of :func:`split_materials`): point data ``rho2`` (the nodal ρ̄2),
      cell data ``material`` (1 ``soft``, 2 ``stiff``), ``material_soft``,
      ``material_stiff`` (1 in that material's cells, else 0) and, given the ``problem``,
      ``E`` (Pa: E1 or E2);
    * point data ``p`` (Pa, pressure cases) and ``u`` (m): the run's Darcy pressure and
      displacement at the points;
    * cell data of the run model's strain and stress measures
      (:func:`~pacto_ng.measures.strain_stress_measures`: ``strain`` and ``stress`` (σ) for a
      linear run, Green–Lagrange ``E_GL`` and second Piola–Kirchhoff ``S`` for the
      hyperelastic ones, ``E_W1``, ``E_W2``, ``S`` for Wang): the element means of the source
      element (design.vtu's values), each a symmetric tensor of 6 components in VTK's order xx,
      yy, zz, xy, yz, xz.

    Returns ``(solid, notes)``.  A run that stopped on a Newton failure has no equilibrium at
    its load: ρ̄ and p only, and ``notes`` says so.  ValueError when a point of the part is not
    found in the run's mesh or a field is not finite."""
    from ngsolve import GridFunction

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
        solid.point_data["p"] = np.asarray(problem.pressure_block.pressure(mips)).ravel()
    notes = []
    if problem.failure:
        notes.append("no displacement, strain or stress: the run's own model has no "
                     f"equilibrium on its final design at the full load ({problem.failure})")
    else:
        solid.point_data["u"] = np.asarray(problem.mech.u(mips)).reshape(-1, 3)
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


def stiff_sampler(solid, threshold2: float):
    """A two-material part's rule for the remesh (:func:`~.remesh3d.remesh_part`'s
    ``stiff_at``): points -> whether the nodal ρ̄2, interpolated linearly in the clipped
    ``solid`` (point data :data:`RHO2`), reaches ``threshold2``; a point outside the solid
    (the smoothed surface runs up to a fraction of an element outside the clipped one) takes
    the value at the solid's nearest vertex."""
    import pyvista as pv

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
