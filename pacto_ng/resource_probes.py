"""The measurements behind :mod:`pacto_ng.resources`'s numbers (this 2-core, 23 GB machine,
ngsolve 6.2.2608), and the probes that take them again: ``python -c 'from
pacto_ng.resource_probes import measure; measure(2)'`` (``measure(3)``: hours of CPU at the
largest sizes), each probe in a fresh process (its peak RSS is the process's).

**Elements.**  2D: a 2 x 1 rectangle at h = 0.04 ... 0.005 gave 2874, 11 542, 46 176,
184 662 triangles (2.299–2.309·A/h²); an edge's smaller ``maxh`` he added 5.5–6.5·L/he on a
unit square (h = 0.05, he = 0.01 ... 0.002).  3D: fitted on the shapes ``cube``, ``slab``,
``bar`` and ``holed`` (a 2 x 1 x 1 box with a cylindrical hole of radius 0.25;
:func:`probe_shape`) at 2–4 sizes each, 648 to 73 813 tetrahedra (:func:`probe_tets`,
:func:`fit_tets`): ``n·h³/V`` = 4.27–8.03, geometric mean 5.12; 5 gives 0.62–1.17 of Netgen's
count on them.  The spread is Netgen's: its count is not monotone in ``h`` (the slab: 4.36 at
h = 0.05, 6.33 at 0.035), and a curved face within a few elements of its radius is refined
(the holed box at h = 0.2: 8.03).  On shapes not fitted (``chamber``, ``sphere``,
``lbracket``, and the 2 x 1 x 1 box of the memory probes) the estimate is 0.59–1.53 of
Netgen's count.

**Memory** (:func:`probe_solve`, :func:`fit_memory`).  2D: linear elasticity on VectorH1,
orders 1–3, Netgen triangles (2 x 1 rectangle, h = 0.04, 0.02, 0.01, 0.005) and structured
quads (2n x n, n = 25, 50, 100, 200), 2.6·10³ to 1.7·10⁶ dofs, sparse Cholesky and UMFPACK (a
follower pressure's unsymmetric tangent), two threads; e.g. 1.67·10⁶ dofs (order 3, 184 662
triangles): 3.56 GB with Cholesky, 8.81 GB with UMFPACK; 1.44·10⁶ dofs (order 3, 200 x 100
quads): 3.73 and 7.55 GB.  3D (one thread): a 2 x 1 x 1 box, Netgen tetrahedra (h = 0.3 ...
0.035) and 2n x n x n hexahedra (n = 8 ... 24) at orders 1–3, 5·10³ to 3.2·10⁵ dofs,
factorised (``sparsecholesky``, ``umfpack``: 12 and 11 points above 2·10⁴ dofs) or assembled
with the BDDC preconditioner of the iterative route as :class:`pacto_ng.physics.solvers.
LinearSolver` builds it (``iterative``, orders 2–3: its coarse vertex problem factorised; 10
points); e.g. 1.51·10⁵ dofs (order 1, 271 359 tetrahedra): 2.68 GB with Cholesky (factorised
in 84 s), 6.65 GB with UMFPACK (225 s); 9.2·10⁴ dofs on 48 x 24 x 24 hexahedra: 1.84 and 3.83
GB; with BDDC, 2.1·10⁵ dofs (order 2, 32 x 16 x 16 hexahedra): 1.44 GB, 3.2·10⁵ (order 2,
73 721 tetrahedra): 1.26 GB.  At 4.4·10⁴ dofs the 3D Cholesky takes 0.43 GB where the 2D fit
gives 0.05 GB.  Below 2·10⁴ dofs the measured is 0.94–1.29 of the 3D fit (fixed costs).

**Whole runs** (``pacto run ... --set iterations=2``, peak RSS by ``/usr/bin/time``, less the
0.22 GB of a default mbb run), estimate / measured::

    run                                                    dofs      measured  est/meas
    mbb --nelx 400 --nely 300 --order 3                   2 164 202   6.71 GB   1.00
    mbb --nelx 200 --nely 100 --order 1                      40 602   0.20 GB   1.29
    mbb --nelx 200 --nely 100 --order 2                     161 202   0.87 GB   1.40
    mbb --nelx 200 --nely 100 --order 3                     361 802   0.85 GB   2.22
    pa-inverter --maxh 0.002 --order 1                       11 894   0.09 GB   0.96
    pa-inverter --maxh 0.002 --order 2                       46 970   0.26 GB   1.20
    pa-inverter --maxh 0.001 --order 2                      185 914   1.11 GB   1.14
    pa-inverter --maxh 0.002 --order 2, Neo-Hookean,         46 970   0.22 GB   1.95
      load_type=follower (UMFPACK)
    pa-inverter --maxh 0.001 --order 1, the same             46 780   0.31 GB   1.35

3D: ``pacto run cantilever-3d --maxh 0.012 --order 1 --iterations 2`` (85 141 tetrahedra
against 90 422 estimated, 53 115 dofs, Cholesky): peak RSS 1.82 GB above the 0.12 GB of the
imports, the estimate from its counts 2.04 GB (1.12); ``--maxh 0.02 --order 2`` (15 977
tetrahedra against 19 531 estimated, 78 219 dofs, CG + BDDC, no element matrices): 0.86 GB,
the estimate from its counts 0.61 GB (0.71: the iterative run holds more around its system
than :func:`~pacto_ng.estimate.run_overheads` counts; one run, not refitted).

**The outputs.**  Writing design.vtu (NGSolve's ``VTKOutput``: x, ρ̄, u and the twelve strain
and stress components, each element subdivided once above order 1) raises a large 3D run's
peak above its iterations': on ``pacto run cantilever-3d --maxh 0.0085 --order 2
--iterations 3`` (308 738 tetrahedra, 1 316 703 dofs, CG + BDDC) the process's high-water
mark went from 6.00 GB after the iterations and the summary to 7.41 GB in design.vtu's 15.6 s
(measured around each output, 2026-12-04), about 460 bytes per point written (10 per
tetrahedron).  With it the estimate from the run's counts is 7.74 GB against the measured
peak of 7.41 GB (1.04; without it 6.32 GB, 0.85); on ``--maxh 0.0092`` (133 774 tetrahedra,
603 528 dofs) 3.41 GB against 3.20 GB (1.07).

**Meshing time**: Netgen took 0.17–0.26 ms of CPU per triangle (11 542 triangles in 2.7 s,
184 662 in 47 s, on a shared machine) and 0.18–0.31 ms per tetrahedron (up to 0.9 ms on
coarse meshes of curved shapes); the grid builders 17–20 µs per quad (80 000 in 1.3–1.6 s)
and 7–34 µs per hexahedron (128 000 and 16 000 of them, a passive block an eighth of the box).
"""
from __future__ import annotations

import json
import math
import resource
import subprocess
import sys
import time

import numpy as np

from .box import Box, Patch, structured_box
from .estimate import mesh_bytes
from .mesh import Layout, netgen_mesh, structured_mesh
from .physics.solvers import LinearSolver
from .resources import DIMENSIONS

#: the solve probes, by dimension: (mesher, order, sizes: Netgen's h or the grid's n)
_SOLVE_PROBES = {
    2: tuple((mesher, k, sizes) for k in (1, 2, 3)
             for mesher, sizes in (("netgen", (0.04, 0.02, 0.01, 0.005)),
                                   ("grid", (25, 50, 100, 200)))),
    3: (("netgen", 1, (0.1, 0.07, 0.05, 0.035)), ("netgen", 2, (0.2, 0.14, 0.1, 0.07)),
        ("netgen", 3, (0.3, 0.2, 0.14, 0.1)), ("grid", 1, (16, 24)), ("grid", 2, (8, 12, 16)),
        ("grid", 3, (8, 12)))}
#: the tetrahedra probes: (shape, sizes)
_TET_PROBES = (("cube", (0.2, 0.1, 0.07, 0.05)), ("slab", (0.1, 0.05, 0.035)),
               ("bar", (0.1, 0.05)), ("holed", (0.2, 0.1, 0.05)))
_THREADS = {2: 2, 3: 1}  # the threads the probes ran with


def _hwm() -> float:
    with open("/proc/self/status") as fh:
        for line in fh:
            if line.startswith("VmHWM:"):
                return float(line.split()[1]) * 1024.0
    raise OSError("no VmHWM in /proc/self/status")


def _cpu() -> float:
    use = resource.getrusage(resource.RUSAGE_SELF)
    return use.ru_utime + use.ru_stime


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


def probe_tets(shape_name: str, maxh: float) -> dict:
    """Mesh a test shape with Netgen tetrahedra at ``maxh``; the count and the CPU time."""
    from netgen import occ

    shape = probe_shape(shape_name)
    cpu = _cpu()
    ngm = occ.OCCGeometry(shape).GenerateMesh(maxh=maxh)
    return {"shape": shape_name, "maxh": maxh, "volume": shape.mass,
            "area": sum(f.mass for f in shape.faces), "tets": ngm.ne, "mesh_cpu_s": _cpu() - cpu}


def _probe_mesh(dim: int, size: float, grid: bool):
    """``(mesh, dirichlet)``: a 2 x 1 rectangle (Netgen triangles of ``size``, or 2n x n
    quads) or a 2 x 1 x 1 box (Netgen tetrahedra, or 2n x n x n hexahedra) fixed on its
    boundary (2D) or its face x = 0 (3D)."""
    from netgen import occ
    from ngsolve import Mesh

    n = int(size)
    if dim == 2:
        return (structured_mesh(Layout(2.0, 1.0), 2 * n, n) if grid
                else netgen_mesh(Layout(2.0, 1.0), size)), "default"
    if grid:
        return structured_box(Box(2.0, 1.0, 1.0, patches=(Patch("fixed", "xmin"),)),
                              2 * n, n, n), "fixed"
    box = occ.Box((0, 0, 0), (2, 1, 1))
    box.faces.Min(occ.X).name = "fixed"
    return Mesh(occ.OCCGeometry(box).GenerateMesh(maxh=size)), "fixed"


def probe_solve(dim: int, size: float, order: int, solver: str, grid: bool = False) -> dict:
    """Linear elasticity on VectorH1 of ``order`` on :func:`_probe_mesh`, assembled and
    factorised with ``solver`` (``sparsecholesky``, ``umfpack``; ``iterative``, 3D: assembled
    with its BDDC preconditioner, as :class:`pacto_ng.physics.solvers.LinearSolver` builds
    it): counts, the meshing's CPU time and memory, the seconds of the factorisation (with the
    assembly for ``iterative``) and the peak RSS above the start."""
    from ngsolve import (BilinearForm, InnerProduct, SetNumThreads, Sym, TaskManager, VectorH1,
                         div, dx, Grad)

    SetNumThreads(_THREADS[dim])
    with TaskManager():
        start, cpu = _hwm(), _cpu()
        mesh, dirichlet = _probe_mesh(dim, size, grid)
        mesh_cpu, after_mesh = _cpu() - cpu, _hwm()
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
    return {"dim": dim, "grid": grid, "size": size, "order": order, "solver": solver,
            "elements": mesh.ne, "dofs": fes.ndof, "mesh_cpu_s": mesh_cpu,
            "mesh_bytes": after_mesh - start, "factor_s": t_fac, "peak_bytes": peak - start}


def _probe(*args) -> dict | None:
    """One probe in a fresh process: ``python -m pacto_ng.resource_probes ARGS``."""
    out = subprocess.run([sys.executable, "-m", "pacto_ng.resource_probes", *map(str, args)],
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
    """``(a, b, q, o)`` of ``bytes − mesh_bytes(elements) = a · ndof^b · q^[grid] · o^k``
    over the solve probes of ``solver`` above 2·10⁴ dofs (least squares in the logs; q = 1
    without grid rows)."""
    sel = [r for r in rows if r["solver"] == solver and r["dofs"] > 20000]
    y = np.log([r["peak_bytes"] - mesh_bytes(r["elements"]) for r in sel])
    X = np.array([[1.0, math.log(r["dofs"]), float(r["grid"]), r["order"]] for r in sel])
    c = np.linalg.lstsq(X, y, rcond=None)[0]
    return float(np.exp(c[0])), float(c[1]), float(np.exp(c[2])), float(np.exp(c[3]))


def measure(dim: int, quick: bool = False) -> list[dict]:
    """Run the probes behind :mod:`pacto_ng.resources`'s numbers of dimension ``dim`` (the
    tetrahedra per volume in 3D; the memory of each solver of its fits over the orders, both
    meshers and :data:`_SOLVE_PROBES`' sizes, ``quick``: the smaller half), print them and
    the fits with measured/fit ranges."""
    rows = []
    if dim == 3:
        tets = [r for name, sizes in _TET_PROBES for h in sizes
                if (r := _probe("tets", name, h)) is not None]
        c = fit_tets(tets)
        print(f"tetrahedra per V/h³: {c:.2f}; estimate/Netgen " + ", ".join(
            f"{r['shape']} {r['maxh']:g}: {c * r['volume'] / r['maxh'] ** 3 / r['tets']:.2f}"
            for r in tets))
    for solver in DIMENSIONS[dim].fits:
        for mesher, k, sizes in _SOLVE_PROBES[dim]:
            if solver == "iterative" and k == 1:  # BDDC at order 1 is a direct solve
                continue
            for size in sizes[:max(len(sizes) // 2, 1)] if quick else sizes:
                r = _probe("solve", dim, size, k, solver, int(mesher == "grid"))
                if r is not None:
                    rows.append(r)
                    print(f"{solver:14s} {mesher:6s} {size:6g} k={k} {r['elements']:7d} el "
                          f"{r['dofs']:8d} dofs  mesh {r['mesh_cpu_s']:5.1f} s CPU  factor "
                          f"{r['factor_s']:6.1f} s  peak {r['peak_bytes'] / 1e6:7.0f} MB",
                          flush=True)
    for solver in DIMENSIONS[dim].fits:
        sel = [r for r in rows if r["solver"] == solver and r["dofs"] > 20000]
        if len(sel) >= 4:
            a, b, q, o = fit_memory(rows, solver)
            ratio = [(r["peak_bytes"] - mesh_bytes(r["elements"]))
                     / (a * r["dofs"] ** b * q ** r["grid"] * o ** r["order"]) for r in sel]
            print(f"{solver}: a = {a:.4g}, b = {b:.4f}, q = {q:.3f}, o = {o:.4f}; "
                  f"measured/fit {min(ratio):.2f}-{max(ratio):.2f} ({len(sel)} points)")
    return rows


if __name__ == "__main__":
    if sys.argv[1] == "tets":
        print(json.dumps(probe_tets(sys.argv[2], float(sys.argv[3]))))
    else:  # solve DIM SIZE ORDER SOLVER GRID
        print(json.dumps(probe_solve(int(sys.argv[2]), float(sys.argv[3]), int(sys.argv[4]),
                                     sys.argv[5], grid=sys.argv[6] == "1")))
