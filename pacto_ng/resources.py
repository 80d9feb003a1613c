"""Resources checked before they run out: a run's elements, displacement dofs, peak memory and
meshing time, estimated from the mesh options and the element order *before* any mesh is made,
and refused with one line (an :class:`~pacto_ng.params.InputError`, exit code 2 from the CLI)
when they do not fit this machine.  One path for 2D and 3D: the dimension comes from the mesh
or the geometry, and only the measured numbers differ (:data:`DIMENSIONS`).

:func:`pacto_ng.meshing.mesh_geometry` calls :func:`check` on :func:`estimate_netgen` (Netgen
triangles or tetrahedra: a Layout, a Box, a netgen.occ shape, a CAD file; counted by
:func:`netgen_elements` and :func:`shape_elements`), :func:`estimate_grid` (structured quads
or hexahedra) or, for a mesh that exists (a mesh file after reading, an ``ngsolve.Mesh``),
:func:`estimate_mesh` on its counts.  The remesh of a run's part (``pacto analyse``, ``pacto
export``: :func:`pacto_ng.post.runs.check_part_mesh`) is checked on :func:`estimate_part`, and
the C-beam analysis (``pacto run c-beam``) on the same estimates as a run's mesh.  The
:class:`~pacto_ng.estimate.Estimate` record and a run's memory around its system:
:mod:`pacto_ng.estimate`; the measurements behind the numbers below (on this 2-core, 23 GB
machine, ngsolve 6.2.2608), and the whole runs they were checked on:
:mod:`pacto_ng.resource_probes`.

Estimates
---------
**Elements.**  Netgen elements of size ``h`` in a domain of measure ``A`` (area, volume):
``c·A/h^d``; 2D ``c = 4/√3``, the count of equilateral triangles of side ``h`` (2.299–2.309
measured; 0.99–1.08 of Netgen's count on the built-in cases' geometries,
tests/unit/test_resources.py); 3D ``c = 5`` tetrahedra (a regular one of edge ``h`` fills
``h³/(6√2)``, i.e. 8.5 per h³, but Netgen's interior elements grow larger; 0.59–1.53 of
Netgen's count on shapes not fitted, tests/unit/test_resources_3d.py).  A face's (2D) or
solid's (3D) own ``maxh`` replaces ``h`` in it; in 2D an edge's smaller ``maxh`` ``he`` adds
``6·L/he`` (5.5–6.5 measured), in 3D a face's or edge's smaller ``maxh`` is not counted.
Structured quads or hexahedra: ``nelx·nely(·nelz)``.  A Netgen mesh still to be made of ``n``
elements has about ``n/2`` vertices and ``1.5·n`` edges (2D), or ``n/5`` vertices (4.9–5.0
measured), ``n/5 + n`` edges and ``2n`` faces (3D).

**Displacement dofs** (``d``-vector H1 of order k, NGSolve's: full tensor-product polynomials
on quads and hexahedra): ``d·(nv + (k−1)·nedge + (k−1)(k−2)/2·ntrig + (k−1)²·nquad +
(k−1)(k−2)(k−3)/6·ntet + (k−1)³·nhex)`` (in 3D ntrig, nquad count faces); for a Netgen mesh
still to be made in 2D about ``k²·n`` (0.94–1.03 of the real count); exact for a grid
(``d·Π(k·nel+1)``) and for a mesh that exists.

**Memory.**  The largest allocation of a run is the displacement system, assembled and
factorised (or, in 3D on the iterative route, assembled with its BDDC preconditioner): its
peak RSS above the process's start, fitted as ``bytes − mesh = a · ndof^b · q^[quads or
hexahedra] · o^k`` (points above 2·10⁴ dofs)::

    2D  sparsecholesky  a = 447    b = 1.074  q = 1.17  o = 1.170   measured/fit 0.91–1.10
        umfpack         a = 1182   b = 1.051  q = 1.11  o = 1.272   measured/fit 0.89–1.13
    3D  sparsecholesky  a = 57.6   b = 1.463  q = 1.58  o = 1.093   measured/fit 0.89–1.13
        umfpack         a = 152.7  b = 1.452  q = 1.38  o = 1.134   measured/fit 0.91–1.13
        iterative       a = 1261   b = 1.047  q = 2.09  o = 1.226   measured/fit 0.92–1.07

Fill-in is far larger in 3D: a nested-dissection factorisation of a 3D mesh grows like
``ndof^(4/3)`` and more (at 1.5·10⁵ dofs the 3D Cholesky takes 2.7 GB, the 2D fit gives 0.19
GB).  Which route a 3D system takes is the physics' (:func:`route`:
:func:`pacto_ng.physics.routes.choose`; with ``solver = auto`` direct at order 1 and up to
``DIRECT_MAX_DOFS_3D`` dofs, iterative above it at order ≥ 2); 2D systems are estimated as
factorised.  A run holds more around its system: the mesh, the linear fast paths' element
matrices while they are built (on the iterative route the displacement's up to 10⁸
entries), and the pressure's and filter's
systems, MMA and the outputs (:func:`pacto_ng.estimate.run_overheads`); in 3D writing
design.vtu adds about 460 bytes per point written (4 or 10 per tetrahedron, 8 or 27 per
hexahedron, order 1 or above).  This machine (23 GB, about 18 GB usable) plans 3D runs up to
about 5·10⁵ dofs with Cholesky at order 1.

**Limit**: :func:`memory_limit`, ``_SAFETY`` (80 %) of the least of MemAvailable, the
physical memory, the cgroup's memory limit less its usage (v1 or v2), and the address-space
limit (``ulimit -v``) less the process's size.

**Meshing time** grows with the element count: Netgen took 0.17–0.26 ms of CPU per triangle
and 0.18–0.31 ms per tetrahedron (up to 0.9 ms on coarse meshes of curved shapes), the
structured grid builders 17–20 µs per quad and 7–34 µs per hexahedron.  A mesh whose making
alone would exceed the ``mesh_time_limit`` setting (:data:`MESH_TIME_LIMIT`, 300 s: about
1.5·10⁶ Netgen triangles or 1.5·10⁷ quads) is refused before it is started; ``--set
mesh_time_limit=SECONDS`` allows longer.
"""
from __future__ import annotations

import math
import os
import resource
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .errors import InputError
from .estimate import Estimate, mesh_bytes, run_overheads
from .geometry import is_solid
from .physics.routes import choose


@dataclass(frozen=True)
class Dimension:
    """The numbers of one dimension (module docstring; measured: :mod:`pacto_ng.
    resource_probes`)."""

    fits: dict              # the displacement system's memory, by solver: (a, b, quad/hex, order)
    netgen_density: float   # Netgen elements per h^d of area or volume
    elements_per_vertex: float  # a Netgen mesh still to be made: its elements per vertex,
    netgen_counts: dict     # and its edges, faces (trigs) and tetrahedra per element
    netgen_seconds: float   # CPU seconds per Netgen element
    kinds: tuple            # (simplices, boxes): what the elements are called
    netgen_types: tuple     # Netgen's element type codes (simplex, box)
    edge_elements: float = 0.0  # extra elements per length/he along an edge of smaller maxh
    output_points: tuple = ()   # design.vtu's points per element: (simplex, box) x (k = 1, k > 1)


DIMENSIONS = {
    2: Dimension(fits={"sparsecholesky": (447.2, 1.0735, 1.168, 1.1697),
                       "umfpack": (1181.7, 1.0512, 1.108, 1.2717)},
                 netgen_density=4.0 / math.sqrt(3.0), elements_per_vertex=2,
                 netgen_counts={"edges": 1.5, "trigs": 1.0}, netgen_seconds=2.0e-4,
                 kinds=("triangles", "quads"), netgen_types=(10, 11), edge_elements=6.0),
    3: Dimension(fits={"sparsecholesky": (57.55, 1.4627, 1.582, 1.0925),
                       "umfpack": (152.7, 1.4516, 1.384, 1.1340),
                       "iterative": (1261.0, 1.0466, 2.089, 1.2257)},
                 netgen_density=5.0, elements_per_vertex=5,
                 netgen_counts={"edges": 1.2, "trigs": 2.0, "tets": 1.0}, netgen_seconds=2.5e-4,
                 kinds=("tetrahedra", "hexahedra"), netgen_types=(20, 25),
                 output_points=((4, 10), (8, 27))),
}
_SAFETY = 0.8               # of the free memory a run may plan to use
_GRID_SECONDS = 2.0e-5      # CPU seconds per structured quad or hexahedron
_OUTPUT_BYTES_PER_POINT = 460.0  # design.vtu's writing, per point (module docstring)
MESH_TIME_LIMIT = 300.0     # default of the mesh_time_limit setting, seconds
_HUGE = 1e300               # counts are capped here (a maxh of 1e-300 still gives one line)


def route(dofs: float, order: int, dim: int, linear_solver: str = "auto") -> str:
    """``"direct"`` or ``"iterative"``: the displacement system's route as the physics takes
    it (:func:`pacto_ng.physics.routes.choose`; ``linear_solver`` its ``solver`` setting)."""
    return choose(linear_solver, int(min(dofs, 1e18)), dim, max(int(order), 1))


def run_memory(dofs: float, order: int, elements: float, dim: int, *, boxes: bool = False,
               solver: str | None = None, linear_solver: str = "auto") -> float:
    """A run's peak memory in bytes (above the process's start) for ``dofs`` displacement
    dofs of ``order`` on ``elements`` simplices (or, ``boxes``, quads or hexahedra): the
    displacement system's fit for its :func:`route` (where the dimension has an iterative fit;
    direct: ``solver``, ``sparsecholesky``, ``umfpack`` or None for the larger, umfpack's) and
    what a run holds around it (:func:`pacto_ng.estimate.run_overheads`, design.vtu)."""
    d, k = DIMENSIONS[dim], max(int(order), 1)
    direct = "iterative" not in d.fits or route(dofs, k, dim, linear_solver) == "direct"
    a, b, q, o = d.fits[(solver or "umfpack") if direct else "iterative"]
    system = a * min(max(dofs, 1.0), 1e30) ** b * (q if boxes else 1.0) * o ** k
    local = (k + 1) ** dim if boxes else math.comb(k + dim, dim)  # scalar dofs per element
    memory = run_overheads(system, elements, local, dim=dim, iterative=not direct)
    if d.output_points:
        points = d.output_points[bool(boxes)][k > 1]
        memory += _OUTPUT_BYTES_PER_POINT * points * min(elements, _HUGE)
    return memory


def vector_h1_dofs(order: int, dim: int, *, vertices: float, edges: float, trigs: float = 0.0,
                   quads: float = 0.0, tets: float = 0.0, hexes: float = 0.0) -> float:
    """Dofs of a ``dim``-vector H1 space of ``order`` on a mesh with these counts (in 3D
    ``trigs`` and ``quads`` count faces)."""
    k = max(int(order), 1)
    return dim * (vertices + (k - 1) * edges + (k - 1) * (k - 2) / 2 * trigs
                  + (k - 1) ** 2 * quads + (k - 1) * (k - 2) * (k - 3) / 6 * tets
                  + (k - 1) ** 3 * hexes)


def netgen_elements(measure: float, maxh: float, dim: int) -> float:
    """Netgen triangles (tetrahedra) of size ``maxh`` on a face of area (in a solid of
    volume) ``measure`` (module docstring; ``inf`` for a ``maxh`` so small that the count
    overflows)."""
    n = DIMENSIONS[dim].netgen_density * (measure / maxh)
    for _ in range(dim - 1):
        n /= maxh
    return n


def shape_elements(shape, maxh: float) -> float:
    """Netgen elements of a netgen.occ ``shape`` at ``maxh``, tetrahedra of a 3D one (it holds
    solids), triangles of a 2D one: each solid's volume (face's area) at the smaller of
    ``maxh`` and its own ``maxh``, and in 2D ``6·L/he`` along each edge whose ``maxh`` ``he``
    is smaller (module docstring).  Cheap: areas, volumes and lengths from OCC, no meshing."""
    dim = 3 if is_solid(shape) else 2
    d = DIMENSIONS[dim]
    n = 0.0
    for part in shape.solids if dim == 3 else shape.faces:
        n += netgen_elements(part.mass, min(maxh, part.maxh), dim)
    for edge in shape.edges if d.edge_elements else ():
        if edge.maxh < maxh:
            n += d.edge_elements * edge.mass / edge.maxh
    return n


def estimate_netgen(elements: float, order: int, dim: int, *, solver: str | None = None,
                    linear_solver: str = "auto") -> Estimate:
    """A Netgen mesh still to be made of about ``elements`` triangles or tetrahedra
    (:func:`netgen_elements`, :func:`shape_elements`), its vertices, edges and faces from
    them (module docstring)."""
    d = DIMENSIONS[dim]
    n = min(float(elements), _HUGE)  # a maxh so small that the count overflows
    dofs = vector_h1_dofs(order, dim, vertices=n / d.elements_per_vertex,
                          **{key: c * n for key, c in d.netgen_counts.items()})
    return Estimate(n, dofs, run_memory(dofs, order, n, dim, solver=solver,
                                        linear_solver=linear_solver),
                    d.netgen_seconds * n, max(int(order), 1), d.kinds[0], "Netgen")


def estimate_part(measure: float, maxh: float, order: int | None = None, *, dim: int,
                  solver: str | None = None) -> Estimate:
    """The Netgen remesh at ``maxh`` of a part of about ``measure`` (area, volume: a
    thresholded design, ``pacto analyse``, ``pacto export``): with ``order``, a re-analysis on
    it (its memory as a run's, :func:`estimate_netgen`); None: the mesh alone
    (:func:`~pacto_ng.estimate.mesh_bytes`, no displacement system).  Against Netgen's count
    on pa-inverter parts (from the design's Σ a ρ̄, maxh 0.005-0.001): 0.80-1.67 (a remesh's
    parts are graded, thin members and boundaries fill unevenly)."""
    elements = netgen_elements(measure, maxh, dim)
    if order is not None:
        return estimate_netgen(elements, order, dim, solver=solver)
    d, n = DIMENSIONS[dim], min(float(elements), _HUGE)
    return Estimate(n, 0.0, mesh_bytes(n), d.netgen_seconds * n, 0, d.kinds[0], "Netgen")


def estimate_grid(nel, order: int, *, solver: str | None = None,
                  linear_solver: str = "auto") -> Estimate:
    """A structured mesh of ``nel`` = ``(nelx, nely)`` quads or ``(nelx, nely, nelz)``
    hexahedra (:func:`pacto_ng.mesh.structured_mesh`, :func:`pacto_ng.box.structured_box`):
    counted exactly."""
    dim, k = len(nel), max(int(order), 1)
    n = math.prod(map(float, nel))
    dofs = math.prod((k * m + 1 for m in nel), start=float(dim))
    return Estimate(n, dofs, run_memory(dofs, k, n, dim, boxes=True, solver=solver,
                                        linear_solver=linear_solver),
                    _GRID_SECONDS * n, k, DIMENSIONS[dim].kinds[1], "the grid builder",
                    exact=True)


def estimate_mesh(mesh, order: int, *, solver: str | None = None,
                  linear_solver: str = "auto") -> Estimate:
    """A mesh that exists (an ``ngsolve.Mesh``, 2D or 3D): elements and dofs counted."""
    counts, simplices, boxes, size = _element_counts(mesh)
    dofs = vector_h1_dofs(order, mesh.dim, vertices=mesh.nv, edges=mesh.nedge, **counts)
    names = DIMENSIONS[mesh.dim].kinds
    kind = names[1] if boxes == size else names[0] if simplices == size else "elements"
    return Estimate(mesh.ne, dofs, run_memory(dofs, order, mesh.ne, mesh.dim,
                                              boxes=boxes > simplices, solver=solver,
                                              linear_solver=linear_solver),
                    0.0, max(int(order), 1), kind, None, exact=True)


def _element_counts(mesh) -> tuple[dict, int, int, int]:
    """``(counts, simplices, boxes, elements)`` of a mesh that exists, ``counts`` those of
    :func:`vector_h1_dofs`: a 2D mesh's elements are its trigs and quads (any element not a
    quad a trig); a 3D mesh's faces are counted one by one where it mixes elements."""
    simplex, box = DIMENSIONS[mesh.dim].netgen_types
    elements = mesh.ngmesh.Elements2D() if mesh.dim == 2 else mesh.ngmesh.Elements3D()
    types = np.asarray(elements.NumPy()["type"])
    boxes = int(np.count_nonzero(types == box))
    size = int(types.size)
    if mesh.dim == 2:
        return {"trigs": size - boxes, "quads": boxes}, size - boxes, boxes, size
    simplices = int(np.count_nonzero(types == simplex))
    if boxes == size:
        quad_faces = mesh.nface
    elif simplices == size:
        quad_faces = 0
    else:
        quad_faces = sum(1 for f in mesh.faces if len(f.vertices) == 4)
    counts = {"trigs": mesh.nface - quad_faces, "quads": quad_faces, "tets": simplices,
              "hexes": boxes}
    return counts, simplices, boxes, size


# ------------------------------------------------------------------------------------------
def memory_limit() -> tuple[float, str]:
    """``(bytes, what)``: the memory a run may plan to use, ``_SAFETY`` of the smallest of
    MemAvailable, the physical memory, the cgroup's limit less its usage and ``ulimit -v``
    less the process's size; ``what`` names the one that decided."""
    free = []
    try:
        free.append((os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"),
                     "physical memory"))
    except (ValueError, OSError, AttributeError):
        pass
    meminfo = _read_kib("/proc/meminfo", "MemAvailable:")
    if meminfo is not None:
        free.append((meminfo, "available memory"))
    cgroup = _cgroup_free()
    if cgroup is not None:
        free.append((cgroup, "cgroup's memory limit less its usage"))
    soft, _ = resource.getrlimit(resource.RLIMIT_AS)
    if soft != resource.RLIM_INFINITY:
        size = _read_kib("/proc/self/status", "VmSize:") or 0.0
        free.append((max(soft - size, 0.0),
                     "address-space limit (ulimit -v) less the process's size"))
    if not free:
        return math.inf, "unknown"
    amount, what = min(free)
    return _SAFETY * amount, f"{_SAFETY:.0%} of the {what}, {_bytes(amount)}"


def _read_kib(path: str, key: str) -> float | None:
    try:
        with open(path) as fh:
            for line in fh:
                if line.startswith(key):
                    return float(line.split()[1]) * 1024.0
    except (OSError, ValueError, IndexError):
        return None
    return None


def _cgroup_free() -> float | None:
    """The process's cgroup memory limit less its usage (v2 ``memory.max``, v1
    ``memory.limit_in_bytes``); None without a finite limit."""
    try:
        lines = Path("/proc/self/cgroup").read_text().splitlines()
    except OSError:
        return None
    best = None
    for line in lines:
        parts = line.split(":", 2)
        if len(parts) != 3:
            continue
        hier, controllers, rel = parts
        rel = rel.lstrip("/")
        if hier == "0" and controllers == "":
            roots, files = [Path("/sys/fs/cgroup") / rel, Path("/sys/fs/cgroup")], \
                ("memory.max", "memory.current")
        elif "memory" in controllers.split(","):
            roots, files = [Path("/sys/fs/cgroup/memory") / rel, Path("/sys/fs/cgroup/memory")], \
                ("memory.limit_in_bytes", "memory.usage_in_bytes")
        else:
            continue
        for root in roots:
            try:
                limit_text = (root / files[0]).read_text().strip()
                usage = float((root / files[1]).read_text().strip())
            except (OSError, ValueError):
                continue
            if limit_text == "max":
                break
            try:
                limit = float(limit_text)
            except ValueError:
                break
            if limit >= 2 ** 60:  # v1's "no limit"
                break
            left = max(limit - usage, 0.0)
            best = left if best is None else min(best, left)
            break
    return best


# ------------------------------------------------------------------------------------------
def _bytes(n: float) -> str:
    if n >= 1e15:
        return f"{n:.2g} bytes"
    for unit, size in (("TB", 1e12), ("GB", 1e9), ("MB", 1e6)):
        if n >= size:
            return f"{n / size:.3g} {unit}"
    return f"{n / 1e3:.3g} kB"


def _count(n: float) -> str:
    return f"{n:,.0f}" if n < 1e7 else f"{n:.2g}"


def duration(s: float) -> str:
    """Seconds said in the unit that reads best (s, min, h, days, years)."""
    if s < 10:
        return f"{s:.2g} s"
    if s < 120:
        return f"{s:.0f} s"
    if s < 7200:
        return f"{s / 60:.0f} min"
    if s < 48 * 3600:
        return f"{s / 3600:.1f} h"
    return f"{s / 86400:.2g} days" if s < 3e9 else f"{s / 3.15e7:.2g} years"


def check(est: Estimate, what: str, *, mesh_time_limit: float = MESH_TIME_LIMIT,
          limit: tuple[float, str] | None = None, advice: str = "",
          longer: str = "--set mesh_time_limit=SECONDS to allow longer") -> None:
    """Refuse ``est`` with one line (an InputError) when its memory exceeds the limit
    (:func:`memory_limit` unless given) or, for a mesh still to be made, its meshing time
    exceeds ``mesh_time_limit`` seconds.  ``what`` names the setting that decided the mesh
    (``maxh = 1e-05``, ``nelx x nely = ...``), ``advice`` what to change, ``longer`` where the
    time limit comes from or how to raise it."""
    limit_bytes, limit_what = limit if limit is not None else memory_limit()
    too_big = est.memory > limit_bytes
    too_slow = est.mesher is not None and est.mesh_seconds > mesh_time_limit
    if not (too_big or too_slow):
        return
    about = "" if est.exact else "about "
    line = f"{what}: {about}{_count(est.elements)} {est.kind}"
    if est.order:
        line += f", {_count(est.dofs)} displacement dofs at order {est.order}"
    if too_big:
        needs = "a run needs" if est.order else "the mesh alone needs"
        line += (f"; {needs} about {_bytes(est.memory)} of memory, more than the "
                 f"{_bytes(limit_bytes)} it may use ({limit_what})")
    if too_slow:
        line += (f"; meshing alone would take about {duration(est.mesh_seconds)} of "
                 f"{est.mesher} here, over mesh_time_limit = {mesh_time_limit:g} s ({longer})")
    raise InputError(line + (f"; {advice}" if advice else ""))
