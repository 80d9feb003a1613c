"""Resources checked before they run out: a run's elements, displacement dofs, peak memory and
meshing time, estimated from the mesh options and the element order *before* any mesh is made,
and refused with one line (an :class:`~pacto_ng.params.InputError`, exit code 2 from the CLI)
when they do not fit this machine.

:func:`pacto_ng.meshing.mesh_geometry` calls :func:`check` on :func:`estimate_triangles`
(Netgen: a Layout, a netgen.occ shape, a CAD file), :func:`estimate_grid` (structured quads)
or, for a mesh that exists (a mesh file after reading, an ``ngsolve.Mesh``),
:func:`estimate_mesh` on its counts.  The remesh of a run's part (``pacto analyse``, ``pacto
export``: :func:`pacto_ng.post.runs.check_part_mesh`) is checked on :func:`estimate_part`, and
the C-beam analysis (``pacto run c-beam``) on the same estimates as a run's mesh.

Estimates (2D; 3D meshes: :mod:`pacto_ng.resources3d`; the :class:`~pacto_ng.estimate.Estimate`
record and a run's memory around its system: :mod:`pacto_ng.estimate`; measured on this 2-core,
23 GB machine, ngsolve 6.2.2608)
--------------------------------------------------------------------------
**Elements.**  Netgen triangles of size ``h`` on a face of area ``A``: ``(4/√3)·A/h²``, the
count of equilateral triangles of side ``h`` (a 2 x 1 rectangle at h = 0.04 ... 0.005 gave
2874, 11 542, 46 176, 184 662 triangles: 2.299–2.309·A/h²).  A face's own ``maxh`` replaces
``h`` on it; an edge's smaller ``maxh`` ``he`` adds ``6·L/he`` (5.5–6.5 measured on a unit
square, h = 0.05, he = 0.01 ... 0.002).  On the built-in cases' geometries (Layouts and
netgen.occ shapes, default maxh and half of it) the estimate was 0.99–1.08 of Netgen's count
(tests/unit/test_resources.py).  Structured quads: ``nelx·nely``.

**Displacement dofs** (vector H1 of order k): ``2·(nv + (k−1)·nedge + (k−1)(k−2)/2·ntrig +
(k−1)²·nquad)``; for a triangle mesh still to be made ``nv ≈ ne/2``, ``nedge ≈ 3·ne/2``, i.e.
``k²·ne`` (0.94–1.03 of the real count); for a grid or a mesh that exists, exact.

**Memory.**  The largest allocation of a run is the displacement system, assembled and
factorised.  Its peak RSS (``VmHWM`` above the process's start) was measured by
:func:`measure` (``python -c 'from pacto_ng.resources import measure; measure()'``):
linear elasticity on VectorH1, orders 1–3, Netgen triangles (2 x 1 rectangle, h = 0.04, 0.02,
0.01, 0.005) and structured quads (2n x n, n = 25, 50, 100, 200), 2.6·10³ to 1.7·10⁶ dofs,
sparse Cholesky and UMFPACK (a follower pressure's unsymmetric tangent), and fitted (points
above 2·10⁴ dofs) as ``bytes = a · ndof^b · q^[quads] · o^k``::

    sparsecholesky  a = 447   b = 1.074  q = 1.17  o = 1.170   measured/fit 0.91–1.10
    umfpack         a = 1182  b = 1.051  q = 1.11  o = 1.272   measured/fit 0.89–1.13

(``bytes`` less the mesh, :func:`~pacto_ng.estimate.mesh_bytes`), e.g. 1.67·10⁶ dofs (order
3, 184 662 triangles): 3.56 GB with Cholesky, 8.81 GB with UMFPACK; 1.44·10⁶ dofs (order 3,
200 x 100 quads): 3.73 and 7.55 GB.  A run holds more: the mesh, the linear fast paths'
element matrices while they are built, and the pressure's and filter's systems, MMA and the
outputs (:func:`pacto_ng.estimate.run_overheads`).  Checked on whole runs (``pacto run ...
--set iterations=2``, peak RSS by ``/usr/bin/time``, less the 0.22 GB of a default mbb run),
estimate / measured:

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

**Limit**: :func:`memory_limit`, ``_SAFETY`` (80 %) of the least of MemAvailable, the
physical memory, the cgroup's memory limit less its usage (v1 or v2), and the address-space
limit (``ulimit -v``) less the process's size.

**Meshing time** grows with the element count: Netgen took 0.17–0.26 ms of CPU per triangle
here (11 542 triangles in 2.7 s, 184 662 in 47 s, on a shared machine), the structured grid
builder 17–20 µs per quad (80 000 in 1.3–1.6 s).  A mesh whose making alone would exceed the
``mesh_time_limit`` setting (:data:`MESH_TIME_LIMIT`, 300 s: about 1.5·10⁶ Netgen triangles or
1.5·10⁷ quads) is refused before it is started; ``--set mesh_time_limit=SECONDS`` allows
longer.
"""
from __future__ import annotations

import math
import os
import resource
import sys
from pathlib import Path

from . import resources3d
from .errors import InputError
from .estimate import Estimate, mesh_bytes, run_overheads
from .mesh import Layout, netgen_mesh, structured_mesh

# the displacement system's memory fit (see the module docstring): (a, b, quad, per order)
_FIT = {"sparsecholesky": (447.2, 1.0735, 1.168, 1.1697),
        "umfpack": (1181.7, 1.0512, 1.108, 1.2717)}
_SAFETY = 0.8               # of the free memory a run may plan to use
_TRIANGLES_PER_AREA = 4.0 / math.sqrt(3.0)  # equilateral triangles of side h per h²
_EDGE_TRIANGLES = 6.0       # extra triangles per length/he along an edge with a smaller maxh
_NETGEN_SECONDS = 2.0e-4    # CPU seconds per Netgen triangle (0.17-0.26 ms measured here)
_GRID_SECONDS = 2.0e-5      # CPU seconds per structured quad (17-20 µs measured here)
MESH_TIME_LIMIT = 300.0     # default of the mesh_time_limit setting, seconds
_HUGE = 1e300               # counts are capped here (a maxh of 1e-300 still gives one line)


def run_memory(dofs: float, order: int, elements: float, *, quads: bool = False,
               solver: str | None = None) -> float:
    """A run's peak memory in bytes (above the process's start) for ``dofs`` displacement
    dofs of ``order`` on ``elements`` elements (module docstring): the displacement system
    (``solver``: ``sparsecholesky``, ``umfpack`` or None for the larger, umfpack's) and what a
    run holds around it (:func:`pacto_ng.estimate.run_overheads`)."""
    k = max(int(order), 1)
    a, b, q, o = _FIT[solver or "umfpack"]
    system = a * min(max(dofs, 1.0), 1e30) ** b * (q if quads else 1.0) * o ** k
    local = (k + 1) ** 2 if quads else (k + 1) * (k + 2) / 2  # scalar dofs per element
    return run_overheads(system, elements, local, dim=2)


def vector_h1_dofs(order: int, *, vertices: float, edges: float, trigs: float = 0.0,
                   quads: float = 0.0, dim: int = 2) -> float:
    """Dofs of a ``dim``-vector H1 space of ``order`` on a 2D mesh with these counts."""
    k = max(int(order), 1)
    return dim * (vertices + (k - 1) * edges + (k - 1) * (k - 2) / 2 * trigs
                  + (k - 1) ** 2 * quads)


def netgen_triangles(area: float, maxh: float) -> float:
    """Netgen triangles of size ``maxh`` on a face of ``area`` (module docstring; ``inf`` for
    a ``maxh`` so small that the count overflows)."""
    return _TRIANGLES_PER_AREA * (area / maxh) / maxh


def estimate_triangles(triangles: float, order: int, *, solver: str | None = None) -> Estimate:
    """A Netgen triangle mesh still to be made, of about ``triangles`` triangles
    (:func:`netgen_triangles`, :func:`shape_triangles`)."""
    n = min(float(triangles), _HUGE)  # a maxh so small that the count overflows
    dofs = vector_h1_dofs(order, vertices=n / 2, edges=1.5 * n, trigs=n)
    return Estimate(n, dofs, run_memory(dofs, order, n, solver=solver), _NETGEN_SECONDS * n,
                    max(int(order), 1), "triangles", "Netgen")


def estimate_part(area: float, maxh: float, order: int | None = None, *,
                  solver: str | None = None) -> Estimate:
    """The Netgen remesh at ``maxh`` of a part of about ``area`` (a thresholded design:
    ``pacto analyse``, ``pacto export``): with ``order``, a re-analysis on it (its memory as a
    run's, :func:`estimate_triangles`); None: the mesh alone (:func:`~pacto_ng.estimate.
    mesh_bytes`, no displacement system).  Against Netgen's count on pa-inverter parts (from the design's
    Σ a ρ̄, maxh 0.005-0.001): 0.80-1.67 (a remesh's parts are graded, thin members and
    boundaries fill unevenly)."""
    triangles = netgen_triangles(area, maxh)
    if order is not None:
        return estimate_triangles(triangles, order, solver=solver)
    n = min(float(triangles), _HUGE)
    return Estimate(n, 0.0, mesh_bytes(n), _NETGEN_SECONDS * n, 0, "triangles", "Netgen")


def shape_triangles(shape, maxh: float) -> float:
    """Netgen triangles of a 2D netgen.occ ``shape`` at ``maxh``: each face's area at the
    smaller of ``maxh`` and its own ``maxh``, plus ``6·L/he`` along each edge whose ``maxh``
    ``he`` is smaller (module docstring).  Cheap: areas and lengths from OCC, no meshing."""
    n = 0.0
    for face in shape.faces:
        n += netgen_triangles(face.mass, min(maxh, face.maxh))
    for edge in shape.edges:
        he = edge.maxh
        if he < maxh:
            n += _EDGE_TRIANGLES * edge.mass / he
    return n


def estimate_grid(nelx: int, nely: int, order: int, *, solver: str | None = None) -> Estimate:
    """A structured ``nelx x nely`` quad mesh."""
    k = max(int(order), 1)
    n = float(nelx) * float(nely)
    dofs = 2.0 * (k * nelx + 1) * (k * nely + 1)
    return Estimate(n, dofs, run_memory(dofs, k, n, quads=True, solver=solver),
                    _GRID_SECONDS * n, k, "quads", "the grid builder", exact=True)


def estimate_mesh(mesh, order: int, *, solver: str | None = None,
                  linear_solver: str = "auto") -> Estimate:
    """A mesh that exists (an ``ngsolve.Mesh``; a 3D one: :func:`pacto_ng.resources3d.
    estimate_mesh`, whose route ``linear_solver`` decides): elements and dofs counted."""
    import numpy as np

    if mesh.dim == 3:
        return resources3d.estimate_mesh(mesh, order, solver=solver, linear_solver=linear_solver)

    types = np.asarray(mesh.ngmesh.Elements2D().NumPy()["type"])
    quads = int(np.count_nonzero(types == 11))  # Netgen's QUAD; TRIG is 10
    trigs = int(types.size) - quads
    dofs = vector_h1_dofs(order, vertices=mesh.nv, edges=mesh.nedge, trigs=trigs, quads=quads)
    kind = "quads" if quads and not trigs else "triangles" if not quads else "elements"
    return Estimate(mesh.ne, dofs, run_memory(dofs, order, mesh.ne, quads=quads > trigs,
                                              solver=solver),
                    0.0, max(int(order), 1), kind, None, exact=True)


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


def _duration(s: float) -> str:
    if s < 120:
        return f"{s:.0f} s"
    if s < 7200:
        return f"{s / 60:.0f} min"
    if s < 48 * 3600:
        return f"{s / 3600:.0f} h"
    if s < 3e9:
        return f"{s / 86400:.2g} days"
    return f"{s / 3.15e7:.2g} years"


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
        line += (f"; meshing alone would take about {_duration(est.mesh_seconds)} of "
                 f"{est.mesher} here, over mesh_time_limit = {mesh_time_limit:g} s ({longer})")
    raise InputError(line + (f"; {advice}" if advice else ""))


# -- the measurements behind the fit --------------------------------------------------------
# python -c 'from pacto_ng.resources import measure; measure()'  (quick=True: the smaller half)
_SIZES = {"netgen": (0.04, 0.02, 0.01, 0.005), "grid": (25, 50, 100, 200)}


def probe(kind: str, size: float, order: int, solver: str) -> dict:
    """Mesh a 2 x 1 rectangle (``netgen``: triangles of size ``size``; ``grid``: 2·size x size
    quads), assemble linear elasticity on VectorH1 of ``order`` and factorise it with
    ``solver``; return the counts, the meshing CPU time and the peak RSS above the start (run it
    in a fresh process: the peak is the process's)."""
    import time

    from ngsolve import (BilinearForm, InnerProduct, SetNumThreads, Sym, TaskManager, VectorH1,
                         div, dx, Grad)

    SetNumThreads(2)
    with TaskManager():
        start = _read_kib("/proc/self/status", "VmHWM:")
        cpu = resource.getrusage(resource.RUSAGE_SELF)
        mesh = (netgen_mesh(Layout(2.0, 1.0), size) if kind == "netgen"
                else structured_mesh(Layout(2.0, 1.0), 2 * int(size), int(size)))
        cpu2 = resource.getrusage(resource.RUSAGE_SELF)
        fes = VectorH1(mesh, order=order, dirichlet="default")
        u, v = fes.TnT()
        a = BilinearForm(fes, symmetric=solver == "sparsecholesky")
        a += (InnerProduct(Sym(Grad(u)), Sym(Grad(v))) + div(u) * div(v)) * dx
        a.Assemble()
        t = time.perf_counter()
        a.mat.Inverse(fes.FreeDofs(), inverse=solver)
        t_fac = time.perf_counter() - t
        peak = _read_kib("/proc/self/status", "VmHWM:")
    return {"kind": kind, "size": size, "order": order, "solver": solver, "elements": mesh.ne,
            "dofs": fes.ndof, "mesh_cpu_s": (cpu2.ru_utime + cpu2.ru_stime)
            - (cpu.ru_utime + cpu.ru_stime), "factor_s": t_fac, "peak_bytes": peak - start}


def measure(quick: bool = False) -> list[dict]:
    """Run :func:`probe` over orders 1-3, both meshers and both solvers (each in a fresh
    process), print each row against :func:`run_memory`'s displacement-system part, and fit
    ``log(bytes - mesh) = log a + b log ndof + [quads] log q + k log o`` per solver."""
    import json
    import subprocess

    import numpy as np

    rows = []
    for solver in ("sparsecholesky", "umfpack"):
        for order in (1, 2, 3):
            for kind, sizes in _SIZES.items():
                for size in sizes[:2] if quick else sizes:
                    code = ("import json; from pacto_ng.resources import probe; "
                            f"print(json.dumps(probe({kind!r}, {size}, {order}, {solver!r})))")
                    out = subprocess.run([sys.executable, "-c", code], capture_output=True,
                                         text=True, timeout=900)
                    if out.returncode != 0:
                        print(f"{kind} {size} order {order} {solver}: failed "
                              f"({out.stderr.strip()[-200:]})")
                        continue
                    row = json.loads(out.stdout.strip().splitlines()[-1])
                    rows.append(row)
                    print(f"{solver:14s} {kind:6s} {size:6g} k={order} {row['elements']:7d} el "
                          f"{row['dofs']:8d} dofs  mesh {row['mesh_cpu_s']:5.1f} s CPU  "
                          f"factor {row['factor_s']:6.1f} s  peak {row['peak_bytes'] / 1e6:7.0f}"
                          " MB", flush=True)
    for solver in ("sparsecholesky", "umfpack"):
        sel = [r for r in rows if r["solver"] == solver and r["dofs"] > 20000]
        if len(sel) < 4:
            continue
        y = np.log([r["peak_bytes"] - mesh_bytes(r["elements"]) for r in sel])
        X = np.array([[1.0, np.log(r["dofs"]), r["kind"] == "grid", r["order"]] for r in sel])
        c = np.linalg.lstsq(X, y, rcond=None)[0]
        ratio = np.exp(y - X @ c)
        print(f"{solver}: a = {np.exp(c[0]):.1f}, b = {c[1]:.4f}, q = {np.exp(c[2]):.3f}, "
              f"o = {np.exp(c[3]):.4f}; measured/fit {ratio.min():.2f}-{ratio.max():.2f}")
    return rows

