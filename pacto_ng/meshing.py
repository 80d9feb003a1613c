"""A case's geometry meshed (:func:`mesh_geometry`): its mesh settings (:class:`MeshSettings`)
and the mesh size derived where a case gives none (:func:`derived_maxh`), each asked of the
geometry's kind (:mod:`pacto_ng.geometry_kinds`, which also checks a mesh against this
machine's resources before it is made).  What the geometry may be: :mod:`pacto_ng.geometry`.
"""
from __future__ import annotations

from dataclasses import dataclass

from . import resources
from .errors import InputError
from .geometry_kinds import Checks, kind_of
from .mesh import Meshed
from .settings import Settings, setting


@dataclass(frozen=True)
class MeshSettings(Settings):
    """How the case's geometry is meshed, and the displacement's element order."""

    maxh: float = setting(0.01, "m", "Netgen element size, triangles or tetrahedra (used when "
                          "nelx = 0)", range="(0, inf)")
    nelx: int = setting(0, "", "structured quads (hexahedra) in x (0: Netgen elements)",
                        range="[0, 100000]")
    nely: int = setting(0, "", "structured quads (hexahedra) in y", range="[0, 100000]")
    nelz: int = setting(0, "", "structured hexahedra in z (a Box; 0 for a 2D domain)",
                        range="[0, 100000]")
    order: int = setting(0, "", "element order of the displacement (1, 2, 3; 0: the case's "
                         "order for the model, see Case.model_orders)", choices=(0, 1, 2, 3))
    unit_elements: bool = setting(False, "", "structured mesh of unit square elements (domain "
                                  "nelx x nely)")
    mesh_time_limit: float = setting(resources.MESH_TIME_LIMIT, "s", "refuse, before "
                                     "meshing, a mesh estimated to take longer to make "
                                     "(pacto_ng/resources.py)", range="(0, inf)")

    def check(self):
        if (self.nelx > 0) != (self.nely > 0):
            raise InputError("nelx, nely: give both (positive) or neither")
        if self.nelz > 0 and self.nelx == 0:
            raise InputError("nelz: needs nelx and nely (a structured hexahedral mesh)")
        if self.unit_elements and self.nelx == 0:
            raise InputError("unit_elements: needs a structured mesh (give --nelx and --nely)")


#: a derived mesh size (``maxh`` given neither by the case nor by the user): this many elements
#: across the smallest side of the domain's bounding box, in 2D and in 3D ...
ACROSS_2D = 30
ACROSS_3D = 10
#: ... coarsened where that would make more elements than this (Netgen's estimate,
#: :mod:`pacto_ng.resources`): a run at defaults stays within minutes (2D: about 0.1 s per
#: linear iteration at 10k triangles here; 3D: the 12-18k-tetrahedron built-in cases take
#: 1-4 min for 150-300 iterations, docs/studies.md)
MAX_DERIVED_TRIANGLES = 40_000
MAX_DERIVED_TETS = 20_000
#: ... and at least this many elements across a filter radius the case gives (the built-in
#: cases have 2.5-4: soft-finger 2.5, pa-inverter 3, pneunet-3d 4)
ACROSS_FILTER = 2.5


def derived_maxh(kind, filter_radius: float = 0.0) -> tuple[float, str] | None:
    """The mesh size of a case that gives none: ``(maxh, how)``, or None where ``maxh`` does
    not apply (a mesh, a mesh file).

    ``side / ACROSS_2D`` (2D) or ``side / ACROSS_3D`` (3D), ``side`` the smallest side of the
    bounding box, or ``filter_radius / ACROSS_FILTER`` where a given filter radius asks for
    finer elements; coarsened to about ``MAX_DERIVED_TRIANGLES`` triangles or
    ``MAX_DERIVED_TETS`` tetrahedra where it would make more (but never coarser than a quarter
    of ``side``), rounded to 3 significant digits.  ``kind``: the geometry's
    (:func:`~pacto_ng.geometry_kinds.kind_of`)."""
    sides = kind.sides
    if sides is None or kind.count(1.0) is None or not min(sides) > 0:
        return None
    dim, side = len(sides), min(sides)
    across = ACROSS_2D if dim == 2 else ACROSS_3D
    cap, what = ((MAX_DERIVED_TRIANGLES, "triangles") if dim == 2 else
                 (MAX_DERIVED_TETS, "tetrahedra"))
    maxh = side / across
    how = f"derived: {across} elements across {side:.3g} m"
    if 0 < filter_radius < ACROSS_FILTER * maxh:
        maxh = filter_radius / ACROSS_FILTER
        how = f"derived: {ACROSS_FILTER:g} elements across the filter radius {filter_radius:.3g} m"
    n = kind.count(maxh)
    if n > cap:  # the count scales as maxh^-dim
        maxh = min(maxh * (n / cap) ** (1.0 / dim), side / 4.0)
        how += f", coarsened to about {cap} {what}"
    return float(f"{maxh:.3g}"), how


def mesh_geometry(geometry, *, maxh: float, nelx: int = 0, nely: int = 0, nelz: int = 0,
                  order: int = 1, mesh_time_limit: float = resources.MESH_TIME_LIMIT,
                  solver: str | None = None, linear_solver: str = "auto") -> Meshed:
    """Mesh a case's geometry (its kinds: :mod:`pacto_ng.geometry_kinds`).

    Netgen triangles (tetrahedra for a 3D shape or a Box) of size ``maxh``; with ``nelx, nely
    > 0`` structured quads, for a :class:`~pacto_ng.mesh.Layout` only, and with ``nelx, nely,
    nelz > 0`` structured hexahedra, for a :class:`~pacto_ng.box.Box` only.

    Before a mesh is made, its elements, its displacement dofs at ``order`` and a run's memory
    are estimated (:mod:`pacto_ng.resources`; ``solver`` of the
    displacement system, ``sparsecholesky`` or ``umfpack``, None for the larger estimate; in
    3D ``linear_solver``, the ``solver`` setting, decides whether the system is factorised or
    solved iteratively, :func:`pacto_ng.resources.route`): a mesh that would not fit this
    machine's memory, or would take Netgen (or the grid builder)
    longer than ``mesh_time_limit`` seconds to make, is refused with one line.  A mesh file or
    an ``ngsolve.Mesh`` is checked on its own counts."""
    return kind_of(geometry).mesh(maxh, (nelx, nely, nelz), order,
                                  Checks(mesh_time_limit, solver, linear_solver))

