"""Resources of 3D meshes, estimated before meshing (the 3D half of :mod:`pacto_ng.resources`;
the :class:`~pacto_ng.estimate.Estimate` record and a run's memory around its system:
:mod:`pacto_ng.estimate`).

:func:`pacto_ng.meshing.mesh_geometry` checks a 3D netgen.occ shape (a Solid, a Glue of
solids, a CAD file holding solids) and a :class:`~pacto_ng.box.Box` meshed as tetrahedra on
:func:`estimate_tets`, a Box meshed as hexahedra on :func:`estimate_hex_grid`, and a 3D mesh
that exists on :func:`estimate_mesh` (:func:`pacto_ng.resources.estimate_mesh` passes 3D meshes
here), each with :func:`pacto_ng.resources.check`: one line naming ``maxh`` or ``nelx x nely x
nelz``, the elements, dofs and memory, before anything is meshed.

Estimates (measured on this 2-core, 23 GB machine, ngsolve 6.2.2608)
-------------------------------------------------------------------
**Tetrahedra.**  Netgen tetrahedra of size ``h`` in a solid of volume ``V``: ``5·V/h³``
(a regular tetrahedron of edge ``h`` fills ``h³/(6√2)``, i.e. 8.5 per h³; Netgen's interior
elements grow larger).  Fitted on the probe shapes ``cube``, ``slab``, ``bar`` and ``holed``
(a 2 x 1 x 1 box with a cylindrical hole of radius 0.25; :func:`probe_shape`) at 2–4 sizes each,
648 to 73 813 tetrahedra: ``n·h³/V`` = 4.27–8.03, geometric mean 5.12; 5 gives 0.62–1.17 of
Netgen's count on them.  The spread is Netgen's: its count is not monotone in ``h`` (the slab:
4.36 at h = 0.05, 6.33 at 0.035), and a curved face within a few elements of its radius is
refined (the holed box at h = 0.2: 8.03).  On shapes not fitted (:func:`probe_shape`
``chamber``, ``sphere``, ``lbracket``, and the 2 x 1 x 1 box of the memory probes), the
estimate is 0.59–1.53 of Netgen's count (tests/unit/test_resources_3d.py).  A solid's own
``maxh`` replaces ``h`` in it; a face's or edge's smaller ``maxh`` is not counted.  Structured
hexahedra: ``nelx·nely·nelz``.  Counts for a mesh still to be made: vertices ``n/5`` (4.9–5.0
measured), edges ``vertices + n``, faces ``2n``.

**Displacement dofs** (3-vector H1 of order k): ``3·(nv + (k−1)·nedge + (k−1)(k−2)/2·ntrig
+ (k−1)²·nquad + (k−1)(k−2)(k−3)/6·ntet + (k−1)³·nhex)`` (faces: ntrig, nquad); exact for a
grid (``3·(k·nelx+1)(k·nely+1)(k·nelz+1)``) and a mesh that exists.

**Meshing time**: Netgen took 0.18–0.31 ms of CPU per tetrahedron (up to 0.9 ms on coarse
meshes of curved shapes), the hexahedral grid builder 7–34 µs per hexahedron (128 000 and
16 000 of them, a passive block an eighth of the box).

**Memory.**  As in 2D the largest allocation is the displacement system, and fill-in is far
larger in 3D: a nested-dissection factorisation of a 3D mesh grows like ``ndof^(4/3)`` and
more (2D: ``ndof^1.07``).  Peak RSS above the start, measured by :func:`probe_solve` (one
process each, one thread) on linear elasticity on a 2 x 1 x 1 box, Netgen tetrahedra (h =
0.3 ... 0.035) at orders 1–3 and 2n x n x n hexahedra (n = 8 ... 24) at orders 1–3, 5·10³ to
3.2·10⁵ dofs, factorised (``sparsecholesky``, ``umfpack``) or assembled with the BDDC
preconditioner of the iterative route as :class:`pacto_ng.physics.solvers.LinearSolver`
builds it (``iterative``, orders 2–3: its coarse vertex problem factorised), and fitted
(points above 2·10⁴ dofs) as ``bytes − mesh = a · ndof^b · q^[hexahedra] · o^k``
(:func:`fit_memory`)::

    sparsecholesky  a = 57.6   b = 1.463  q = 1.58  o = 1.093   measured/fit 0.89–1.13 (12 points)
    umfpack         a = 152.7  b = 1.452  q = 1.38  o = 1.134   measured/fit 0.91–1.13 (11 points)
    iterative       a = 1261   b = 1.047  q = 2.09  o = 1.226   measured/fit 0.92–1.07 (10 points)

e.g. 1.51·10⁵ dofs (order 1, 271 359 tetrahedra): 2.68 GB with Cholesky (factorised in
84 s), 6.65 GB with UMFPACK (225 s); 9.2·10⁴ dofs on 48 x 24 x 24 hexahedra: 1.84 and 3.83
GB; with BDDC, 2.1·10⁵ dofs (order 2, 32 x 16 x 16 hexahedra): 1.44 GB, 3.2·10⁵ (order 2,
73 721 tetrahedra): 1.26 GB.  At 4.4·10⁴ dofs the
3D Cholesky takes 0.43 GB where the 2D fit gives 0.05 GB; at 1.5·10⁵, 2.7 GB against 0.19
GB.  Below 2·10⁴ dofs the measured is 0.94–1.29 of the fit (fixed costs).  The rest of a
run is counted as in 2D (:func:`pacto_ng.estimate.run_overheads`: a factor on the system,
the mesh, the fast paths' element matrices).  Checked on a whole run (``pacto run
cantilever-3d --maxh 0.012 --order 1 --iterations 2``, 85 141 tetrahedra against 90 422
estimated, 53 115 dofs, Cholesky): peak RSS 1.82 GB above the 0.12 GB of the imports, the
estimate from its counts 2.04 GB (1.12); ``--maxh 0.02 --order 2`` (15 977 tetrahedra
against 19 531 estimated, 78 219 dofs, CG + BDDC, no element matrices): 0.86 GB, the
estimate from its counts 0.61 GB (0.71: the iterative run holds more around its system than
:func:`~pacto_ng.estimate.run_overheads` counts; one run, not refitted).  Which route the run takes is the
physics' (:func:`route`: :func:`pacto_ng.physics.solvers.choose`; with ``solver = auto``
direct at order 1 and up to ``DIRECT_MAX_DOFS_3D`` dofs, iterative above it at order ≥ 2).
This machine (23 GB, about 18 GB usable) plans runs up to about 5·10⁵ dofs with Cholesky at
order 1.

**The outputs.**  Writing design.vtu (NGSolve's ``VTKOutput``: x, ρ̄, u and the twelve strain
and stress components, each element subdivided once above order 1) raises a large run's peak
above its iterations': on ``pacto run cantilever-3d --maxh 0.0085 --order 2 --iterations 3``
(308 738 tetrahedra, 1 316 703 dofs, CG + BDDC) the process's high-water mark went from 6.00
GB after the iterations and the summary to 7.41 GB in design.vtu's 15.6 s (measured around
each output, 2026-12-04), about 460 bytes per point written (10 per tetrahedron);
:func:`run_memory` adds that per element.  With it the estimate from the run's counts is
7.74 GB against the measured peak of 7.41 GB (1.04; without it 6.32 GB, 0.85); on ``--maxh
0.0092`` (133 774 tetrahedra, 603 528 dofs) 3.41 GB against 3.20 GB (1.07).
"""
from __future__ import annotations

import math
import resource
import sys

from .box import Box, Patch, structured_box
from .estimate import Estimate, mesh_bytes, run_overheads
from .physics.solvers import LinearSolver, choose

# the displacement system's memory fit in 3D (module docstring): (a, b, hexahedra, per order)
_FIT = {"sparsecholesky": (57.55, 1.4627, 1.582, 1.0925),
        "umfpack": (152.7, 1.4516, 1.384, 1.1340),
        "iterative": (1261.0, 1.0466, 2.089, 1.2257)}
_TETS_PER_VOLUME = 5.0      # Netgen tetrahedra per h³ of volume (module docstring)
_NETGEN_SECONDS = 2.5e-4  # CPU seconds per Netgen tetrahedron
_GRID_SECONDS = 2.0e-5    # CPU seconds per structured hexahedron
_HUGE = 1e300                  # counts are capped here (a maxh of 1e-300 still gives one line)
# design.vtu's writing (NGSolve's VTKOutput, subdivided once above order 1), per point it
# writes: 4 (order 1) or 10 (order >= 2) points per tetrahedron, 8 or 27 per hexahedron
# (module docstring, "The outputs")
_OUTPUT_BYTES_PER_POINT = 460.0


def route(dofs: float, order: int, linear_solver: str = "auto") -> str:
    """``"direct"`` or ``"iterative"``: the displacement system's route as the physics takes
    it (:func:`pacto_ng.physics.solvers.choose`; ``linear_solver`` its ``solver`` setting)."""
    return choose(linear_solver, int(min(dofs, 1e18)), 3, max(int(order), 1))


def run_memory(dofs: float, order: int, elements: float, *, hexes: bool = False,
               solver: str | None = None, linear_solver: str = "auto") -> float:
    """A 3D run's peak memory in bytes (above the process's start) for ``dofs`` displacement
    dofs of ``order`` on ``elements`` tetrahedra (or hexahedra): the displacement system's fit
    for its :func:`route` (direct: ``solver``, ``sparsecholesky``, ``umfpack`` or None for the
    larger, umfpack's; iterative: CG or GMRES with BDDC) and the same overheads as in 2D
    (:func:`pacto_ng.estimate.run_overheads`)."""
    k = max(int(order), 1)
    direct = route(dofs, k, linear_solver) == "direct"
    a, b, q, o = _FIT[(solver or "umfpack") if direct else "iterative"]
    system = a * min(max(dofs, 1.0), 1e30) ** b * (q if hexes else 1.0) * o ** k
    local = (k + 1) ** 3 if hexes else (k + 1) * (k + 2) * (k + 3) / 6  # scalar dofs per element
    points = (8 if k == 1 else 27) if hexes else (4 if k == 1 else 10)  # design.vtu's
    return (run_overheads(system, elements, local, dim=3, displacement_matrices=direct)
            + _OUTPUT_BYTES_PER_POINT * points * min(elements, _HUGE))


def vector_h1_dofs(order: int, *, vertices: float, edges: float, trig_faces: float = 0.0,
                   quad_faces: float = 0.0, tets: float = 0.0, hexes: float = 0.0) -> float:
    """Dofs of a 3-vector H1 space of ``order`` on a 3D mesh with these counts (NGSolve's
    H1: full tensor-product polynomials on hexahedra)."""
    k = max(int(order), 1)
    return 3 * (vertices + (k - 1) * edges + (k - 1) * (k - 2) / 2 * trig_faces
                + (k - 1) ** 2 * quad_faces + (k - 1) * (k - 2) * (k - 3) / 6 * tets
                + (k - 1) ** 3 * hexes)


def netgen_tets(volume: float, maxh: float) -> float:
    """Netgen tetrahedra of size ``maxh`` in a solid of ``volume`` (module docstring)."""
    return _TETS_PER_VOLUME * (volume / maxh) / maxh / maxh


def shape_tets(shape, maxh: float) -> float:
    """Netgen tetrahedra of a 3D netgen.occ ``shape`` at ``maxh``: each solid's volume at the
    smaller of ``maxh`` and its own ``maxh`` (a face's or edge's smaller ``maxh`` is not
    counted).  Cheap: volumes from OCC, no meshing."""
    return sum(netgen_tets(solid.mass, min(maxh, solid.maxh)) for solid in shape.solids)


def estimate_tets(tets: float, order: int, *, solver: str | None = None,
                  linear_solver: str = "auto") -> Estimate:
    """A Netgen tetrahedral mesh still to be made, of about ``tets`` tetrahedra: vertices
    ``tets/5``, edges ``vertices + tets``, faces ``2·tets`` (module docstring)."""
    n = min(float(tets), _HUGE)
    dofs = vector_h1_dofs(order, vertices=n / 5, edges=1.2 * n, trig_faces=2 * n, tets=n)
    return Estimate(n, dofs, run_memory(dofs, order, n, solver=solver,
                                        linear_solver=linear_solver),
                    _NETGEN_SECONDS * n, max(int(order), 1), "tetrahedra", "Netgen")


def estimate_hex_grid(nelx: int, nely: int, nelz: int, order: int, *,
                      solver: str | None = None, linear_solver: str = "auto") -> Estimate:
    """A structured ``nelx x nely x nelz`` hexahedral mesh (:func:`pacto_ng.box.
    structured_box`): counted exactly."""
    k = max(int(order), 1)
    n = float(nelx) * float(nely) * float(nelz)
    dofs = 3.0 * (k * nelx + 1) * (k * nely + 1) * (k * nelz + 1)
    return Estimate(n, dofs, run_memory(dofs, k, n, hexes=True, solver=solver,
                                        linear_solver=linear_solver),
                    _GRID_SECONDS * n, k, "hexahedra", "the grid builder", exact=True)


def estimate_mesh(mesh, order: int, *, solver: str | None = None,
                  linear_solver: str = "auto") -> Estimate:
    """A 3D mesh that exists: elements and dofs counted (tetrahedra and hexahedra; a mixed
    mesh's faces are counted one by one)."""
    import numpy as np

    types = np.asarray(mesh.ngmesh.Elements3D().NumPy()["type"])
    hexes = int(np.count_nonzero(types == _NETGEN_HEX))
    tets = int(np.count_nonzero(types == _NETGEN_TET))
    if hexes == types.size:
        trig_faces, quad_faces = 0, mesh.nface
    elif tets == types.size:
        trig_faces, quad_faces = mesh.nface, 0
    else:
        quad_faces = sum(1 for f in mesh.faces if len(f.vertices) == 4)
        trig_faces = mesh.nface - quad_faces
    dofs = vector_h1_dofs(order, vertices=mesh.nv, edges=mesh.nedge, trig_faces=trig_faces,
                          quad_faces=quad_faces, tets=tets, hexes=hexes)
    kind = ("hexahedra" if hexes == types.size else "tetrahedra" if tets == types.size
            else "elements")
    return Estimate(mesh.ne, dofs, run_memory(dofs, order, mesh.ne, hexes=hexes > tets,
                                              solver=solver, linear_solver=linear_solver),
                    0.0, max(int(order), 1), kind, None, exact=True)


_NETGEN_TET, _NETGEN_HEX = 20, 25  # Netgen's element type codes (TET, HEX)


# -- the measurements behind the fits ---------------------------------------------------------
def _hwm() -> float:
    with open("/proc/self/status") as fh:
        for line in fh:
            if line.startswith("VmHWM:"):
                return float(line.split()[1]) * 1024.0
    raise OSError("no VmHWM in /proc/self/status")


def probe_tets(shape_name: str, maxh: float) -> dict:
    """Mesh a test shape with Netgen tetrahedra at ``maxh``; the count and the CPU time."""
    from netgen import occ

    shape = probe_shape(shape_name)
    cpu = resource.getrusage(resource.RUSAGE_SELF)
    ngm = occ.OCCGeometry(shape).GenerateMesh(maxh=maxh)
    cpu2 = resource.getrusage(resource.RUSAGE_SELF)
    return {"shape": shape_name, "maxh": maxh, "volume": shape.mass,
            "area": sum(f.mass for f in shape.faces), "tets": ngm.ne,
            "mesh_cpu_s": (cpu2.ru_utime + cpu2.ru_stime) - (cpu.ru_utime + cpu.ru_stime)}


def probe_shape(name: str):
    """The shapes of the tetrahedra fit and its check."""
    from netgen import occ

    if name == "cube":
        return occ.Box((0, 0, 0), (1, 1, 1))
    if name == "slab":
        return occ.Box((0, 0, 0), (2, 1, 0.25))
    if name == "bar":
        return occ.Box((0, 0, 0), (3, 0.5, 0.5))
    if name == "holed":
        return occ.Box((0, 0, 0), (2, 1, 1)) - occ.Cylinder((1, 0.5, 0), occ.Z, r=0.25, h=1)
    if name == "chamber":
        body = occ.Box((0, 0, 0), (0.1, 0.02, 0.03))
        return body - occ.Cylinder((0.02, 0.01, 0.015), occ.X, r=0.006, h=0.06)
    if name == "sphere":
        return occ.Sphere((0, 0, 0), 1.0)
    if name == "lbracket":
        return occ.Box((0, 0, 0), (2, 2, 0.5)) - occ.Box((1, 1, 0), (2, 2, 0.5))
    raise ValueError(name)


def probe_solve(size: float, order: int, solver: str, hexes: bool = False) -> dict:
    """3D linear elasticity on a 2 x 1 x 1 box (Netgen tets of ``size``, or 2n x n x n
    hexes for ``hexes``), assembled and factorised with ``solver`` (``sparsecholesky``,
    ``umfpack``; ``iterative``: assembled with its BDDC preconditioner, as
    :class:`pacto_ng.physics.solvers.LinearSolver` builds it): counts, the seconds of the
    factorisation (with the assembly for ``iterative``), peak RSS."""
    import time

    from ngsolve import (BilinearForm, InnerProduct, Mesh, SetNumThreads, Sym, TaskManager,
                         VectorH1, div, dx, Grad)
    from netgen import occ

    SetNumThreads(1)
    with TaskManager():
        start = _hwm()
        if hexes:
            n = int(size)
            mesh = structured_box(Box(2.0, 1.0, 1.0, patches=(Patch("fixed", "xmin"),)),
                                  2 * n, n, n)
            dirichlet = "fixed"
        else:
            box = occ.Box((0, 0, 0), (2, 1, 1))
            box.faces.Min(occ.X).name = "fixed"
            mesh = Mesh(occ.OCCGeometry(box).GenerateMesh(maxh=size))
            dirichlet = "fixed"
        after_mesh = _hwm()
        fes = VectorH1(mesh, order=order, dirichlet=dirichlet)
        u, v = fes.TnT()
        a = BilinearForm(fes, symmetric=solver != "umfpack")
        a += (InnerProduct(Sym(Grad(u)), Sym(Grad(v))) + div(u) * div(v)) * dx
        if solver == "iterative":  # CG + BDDC as the physics builds it
            route = LinearSolver(a, fes.FreeDofs(), setting="iterative", order=order)
        t = time.perf_counter()
        a.Assemble()  # the iterative route's preconditioner is built here
        if solver != "iterative":
            a.mat.Inverse(fes.FreeDofs(), inverse=solver)
        else:
            route.prepare()
        t_fac = time.perf_counter() - t
        peak = _hwm()
    return {"hexes": hexes, "size": size, "order": order, "solver": solver,
            "elements": mesh.ne, "dofs": fes.ndof, "mesh_bytes": after_mesh - start,
            "factor_s": t_fac, "peak_bytes": peak - start}


_TET_PROBES = (("cube", (0.2, 0.1, 0.07, 0.05)), ("slab", (0.1, 0.05, 0.035)),
               ("bar", (0.1, 0.05)), ("holed", (0.2, 0.1, 0.05)))
_SOLVE_PROBES = (("netgen", 1, (0.1, 0.07, 0.05, 0.035)), ("netgen", 2, (0.2, 0.14, 0.1, 0.07)),
                 ("netgen", 3, (0.3, 0.2, 0.14, 0.1)), ("hex", 1, (16, 24)),
                 ("hex", 2, (8, 12, 16)), ("hex", 3, (8, 12)))


def _probe(*args) -> dict | None:
    """One probe in a fresh process (its peak RSS is the process's): ``python -m
    pacto_ng.resources3d ARGS``."""
    import json
    import subprocess

    out = subprocess.run([sys.executable, "-m", "pacto_ng.resources3d", *map(str, args)],
                         capture_output=True, text=True, timeout=1800)
    if out.returncode != 0:
        print(f"{' '.join(map(str, args))}: failed ({out.stderr.strip()[-200:]})")
        return None
    return json.loads(out.stdout.strip().splitlines()[-1])


def fit_tets(rows) -> float:
    """The geometric mean of ``n·h³/V`` over the tetrahedra probes ``rows``."""
    q = [r["tets"] * r["maxh"] ** 3 / r["volume"] for r in rows]
    return math.exp(sum(map(math.log, q)) / len(q))


def fit_memory(rows, solver: str) -> tuple[float, float, float, float]:
    """``(a, b, q, o)`` of ``bytes − mesh_bytes(elements) = a · ndof^b · q^[hexes] · o^k``
    over the solve probes of ``solver`` above 2·10⁴ dofs (least squares in the logs)."""
    import numpy as np

    sel = [r for r in rows if r["solver"] == solver and r["dofs"] > 20000]
    y = np.log([r["peak_bytes"] - mesh_bytes(r["elements"]) for r in sel])
    hexes = [float(r["hexes"]) for r in sel]
    X = np.array([[1.0, math.log(r["dofs"]), h, r["order"]] for r, h in zip(sel, hexes)])
    if not any(hexes):  # no hexahedra measured: q = 1
        X[:, 2] = 0.0
    c = np.linalg.lstsq(X, y, rcond=None)[0]
    return float(np.exp(c[0])), float(c[1]), float(np.exp(c[2])), float(np.exp(c[3]))


def measure() -> list[dict]:
    """Run the probes behind the module docstring's fits (each in a fresh process), print
    them and the fits with measured/fit ranges.  Hours of CPU at the largest sizes:
    ``python -c 'from pacto_ng.resources3d import measure; measure()'``."""
    tets = [r for name, sizes in _TET_PROBES for h in sizes
            if (r := _probe("tets", name, h)) is not None]
    c = fit_tets(tets)
    ratios = (f"{r['shape']} {r['maxh']:g}: {c * r['volume'] / r['maxh'] ** 3 / r['tets']:.2f}"
              for r in tets)
    print(f"tetrahedra per V/h³: {c:.2f}; estimate/Netgen " + ", ".join(ratios))
    rows = [r for solver in _FIT for kind, k, sizes in _SOLVE_PROBES for size in sizes
            if not (solver == "iterative" and k == 1)  # BDDC at order 1 is a direct solve
            and (r := _probe(kind, size, k, solver)) is not None]
    for r in rows:
        print(f"{r['solver']:14s} {'hex' if r['hexes'] else 'tet'} {r['size']:6g} k={r['order']} "
              f"{r['elements']:7d} el {r['dofs']:8d} dofs  factor {r['factor_s']:6.1f} s  "
              f"peak {r['peak_bytes'] / 1e6:7.0f} MB")
    for solver in _FIT:
        a, b, q, o = fit_memory(rows, solver)
        print(f"{solver}: a = {a:.4g}, b = {b:.4f}, q = {q:.3f}, o = {o:.4f}")
    return tets + rows


if __name__ == "__main__":
    import json

    kind = sys.argv[1]
    if kind == "tets":
        print(json.dumps(probe_tets(sys.argv[2], float(sys.argv[3]))))
    else:
        print(json.dumps(probe_solve(float(sys.argv[2]), int(sys.argv[3]), sys.argv[4],
                                     hexes=kind == "hex")))
