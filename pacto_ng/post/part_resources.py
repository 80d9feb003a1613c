"""Time and memory of a part's analysis, estimated before the part is meshed or analysed,
and what would not fit this machine refused in one line (``pacto analyse``, step 4 of
:mod:`.analyse`).

The mesh and its memory are :mod:`pacto_ng.resources`'s (:func:`~pacto_ng.resources.
estimate_part` from the design's material area or volume; a mesh that exists, an as-built
part: :func:`~pacto_ng.resources.estimate_mesh`, counted).  The time
is the meshing's and the sweeps': Newton iterations (:func:`analysis_seconds`) times the
seconds of one (:func:`newton_seconds`).
"""
from __future__ import annotations

import dataclasses

from .. import resources
from ..errors import InputError
from .runs import design_density

#: an analysis estimated to take longer than this (seconds) is refused (``--time-limit``)
TIME_LIMIT = 3600.0
#: Newton iterations per pressure, for the estimate: a linear model's deformation-independent
#: kinds take one solve; its follower kind 1-2 (measured on the test parts); a nonlinear model
#: 3-4 from rest at moderate loads, more where a pressure needs load steps
NEWTON_PER_PRESSURE = {"linear": 1, "linear follower": 2, "nonlinear": 5}
#: seconds per element of one tangent assembly with its residual (Neo-Hookean, by (dimension,
#: order)); measured 2026-12-05 on this shared 2-core machine, 2 threads, under load from
#: other sessions: 2D order 2 0.15-0.24 ms (2890 to 46 136 triangles), 3D order 1 0.17-0.41
#: ms (9082 to 117 251 tetrahedra), order 2 0.85 ms (5892); the others scaled by the
#: quadrature points
_ASSEMBLY = {(2, 1): 5e-5, (2, 2): 1.5e-4, (2, 3): 4e-4,
             (3, 1): 3e-4, (3, 2): 9e-4, (3, 3): 2.5e-3}
#: sparse Cholesky factorisation ``s (dofs / n)^b``: (s, n, b) by dimension, from the
#: measurements of docs (NGSOLVE_NOTES: 2D 322k dofs 1.71 s; resource_probes: 3D 1.51e5 dofs 84 s)
_FACTOR = {2: (1.71, 3.22e5, 1.2), 3: (84.0, 1.51e5, 2.0)}
#: UMFPACK (the follower's unsymmetric tangent) against sparse Cholesky (2.5 at 1.5e5 3D dofs,
#: the 3D fits of resources; the measured whole iterations above 1.0-1.7 times the Cholesky ones)
UMFPACK_FACTOR = 2.5


def newton_seconds(elements: float, dofs: float, dim: int, order: int, solver: str) -> float:
    """Seconds of one Newton iteration of a part's analysis: the tangent's assembly
    (:data:`_ASSEMBLY` per element) and its factorisation (:data:`_FACTOR`, times
    :data:`UMFPACK_FACTOR` for ``umfpack``).  Against the measured iterations (module
    constants): 3D order 1, 117 251 tetrahedra, 69 936 dofs: 53 s estimated, 48 s measured;
    46 097, 28 257 dofs: 17 s against 11 s; 2D order 2, 46 136 triangles, 185 746 dofs: 7.8 s
    against 6.9 s."""
    s, n, b = _FACTOR[dim]
    factor = s * (max(float(dofs), 1.0) / n) ** b
    return (_ASSEMBLY[(dim, min(max(int(order), 1), 3))] * float(elements)
            + factor * (UMFPACK_FACTOR if solver == "umfpack" else 1.0))


def analysis_seconds(est, dim: int, kinds, n_pressures: int, model: str) -> tuple[float, int]:
    """``(seconds, Newton iterations)`` of the sweeps on the mesh of ``est``
    (:data:`NEWTON_PER_PRESSURE` per pressure and kind)."""
    total, count = 0.0, 0
    for kind in kinds:
        key = "nonlinear" if model != "linear" else (
            "linear follower" if kind == "follower" else "linear")
        its = n_pressures * NEWTON_PER_PRESSURE[key]
        solver = "umfpack" if kind == "follower" else "sparsecholesky"
        total += its * newton_seconds(est.elements, est.dofs, dim, est.order, solver)
        count += its
    return total, count


#: Newton iterations per pressure with self-contact (pairings until the pairs hold, each a
#: Newton solve; 2026-12-07): from 16 (the 3D slotted block of tests/physics/test_contact.py
#: at 3 kPa, linear, order 1; 26 at order 2, 33 for the 2D one, Neo-Hookean, at 3 kPa after
#: 100 Pa) to 182 (the 2D one loaded on its top face only, Neo-Hookean, at 10 kPa after 3 kPa:
#: walls that slide along each other)
CONTACT_NEWTON_PER_PRESSURE = (16, 182)


def contact_seconds(per_iteration: float, n_pressures: int) -> tuple[float, float]:
    """The least and the most seconds a sweep of ``n_pressures`` with contact may take, from
    the measured seconds of one Newton iteration (:data:`CONTACT_NEWTON_PER_PRESSURE`)."""
    low, high = CONTACT_NEWTON_PER_PRESSURE
    return low * n_pressures * per_iteration, high * n_pressures * per_iteration


def contact_check(per_iteration: float, n_pressures: int, time_limit: float) -> str:
    """The line that says how long a sweep with contact may take (:func:`contact_seconds`);
    InputError where even the lower figure passes ``time_limit``."""
    low, high = contact_seconds(per_iteration, n_pressures)
    dur = resources.duration
    line = (f"with contact: {dur(per_iteration)} per Newton iteration (measured), "
            f"{dur(low)} to {dur(high)} per kind for {n_pressures} "
            f"pressure{'s' if n_pressures != 1 else ''}")
    if low > time_limit:
        raise InputError(f"--contact: {line}, longer than --time-limit {time_limit:g} s; give "
                         f"a larger --maxh, a lower --order or fewer --pressures")
    return line


def check_resources(est, what: str, *, dim: int, kinds, n_pressures: int, model: str,
                    mesh_time_limit: float, time_limit: float = TIME_LIMIT,
                    limit: tuple | None = None) -> float:
    """Refuse with one line (InputError), before the part is meshed or analysed, an analysis
    whose memory (:func:`pacto_ng.resources.memory_limit`), meshing time (over
    ``mesh_time_limit``) or sweeps (:func:`analysis_seconds`, over ``time_limit``) do not fit
    this machine: the line gives the mesh, its dofs, the estimated time and memory and what
    to change.  Returns the estimated seconds."""
    limit_bytes, limit_what = limit if limit is not None else resources.memory_limit()
    sweeps, its = analysis_seconds(est, dim, kinds, n_pressures, model)
    mesh_s = est.mesh_seconds if est.mesher is not None else 0.0
    reasons = []
    if est.memory > limit_bytes:
        reasons.append(f"more memory than the {limit_bytes / 1e9:.3g} GB it may use "
                       f"({limit_what})")
    if mesh_s > mesh_time_limit:
        reasons.append(f"meshing alone over mesh_time_limit = {mesh_time_limit:g} s")
    if sweeps + mesh_s > time_limit:
        reasons.append(f"longer than --time-limit {time_limit:g} s")
    if reasons:
        about = "" if est.exact else "about "
        mesher = f", {resources.duration(mesh_s)} of {est.mesher} meshing" if est.mesher else ""
        raise InputError(
            f"{what}: {about}{est.elements:.3g} {est.kind}, {est.dofs:.3g} displacement dofs "
            f"at order {est.order}; the analysis would take about "
            f"{resources.duration(sweeps + mesh_s)} ({its} Newton iterations of about "
            f"{resources.duration(sweeps / max(its, 1))} each{mesher}) and need about "
            f"{est.memory / 1e9:.3g} GB of memory: " + " and ".join(reasons)
            + "; give a larger --maxh or a lower --order")
    return sweeps + mesh_s


def part_estimate(problem, maxh: float, order: int, kinds, mesh=None):
    """The estimate of a run's part at ``maxh``: before Netgen is asked for it
    (``mesh`` None), from the design's material Σ a ρ̄ (area in 2D, volume in 3D); once
    meshed, counted on ``mesh``.  Its memory is the larger of the part's analysis and the
    design's own at the part's order, on the run's mesh (the expected Δ).  On pneunet-3d's
    part (9267 tetrahedra; its design's mesh, 18 473, the larger system at order 2) this
    gives 5.7 GB against a measured peak of 3.2 GB, on the safe side, where the part's alone
    gave 1.6 GB.  The count from Σ a ρ̄ misses where Netgen fills thin walls finely: about
    7,670 tetrahedra for the 15,025 of the Neo-Hookean pneunet-3d run's part (2026-12-07)."""
    solver = "umfpack" if "follower" in kinds else "sparsecholesky"
    if mesh is None:
        measure = float(problem.field.areas @ design_density(problem))
        part = resources.estimate_part(measure, maxh, order, dim=problem.mesh.dim,
                                       solver=solver)
    else:
        part = resources.estimate_mesh(mesh, order, solver=solver)
    design = resources.estimate_mesh(problem.mesh, order, solver=solver)
    return dataclasses.replace(part, memory=max(part.memory, design.memory))
