"""``--model auto`` and ``load_ramp=-1``: model, and continue, only as much as the load needs.

Both are chosen from one linear analysis of the initial design at the full load: the
Green–Lagrange strain (Frobenius norm of ``E = ½(∇u + ∇uᵀ + ∇uᵀ∇u)``) that 99 % of the
*material* stays below, the quadrature points weighted by the physical density ρ̄ (by ρ̄₁, the
material-or-void density, in a two-material case).  Weighted by the material, not counted
point by point: the void (ρ̄ ≈ 0, stiffness 1e-6 of the solid) strains without limit under a
pressure and carries nothing (measured on the initial designs at the default loads: point by point,
the pa-gripper's 99th percentile is 67 and the mm-gripper's 1627, the material's 7.7e-3 and
6.5e-3).  The 99th percentile, not the maximum:
the corner of a load patch or a clamp is singular in linear elasticity.

- the model: linear below ``STRAIN_THRESHOLD`` (1 %), where the small-strain assumption holds,
  else Wang's interpolation (Neo-Hookean wherever there is material, linear in the void), the
  nonlinear model that carries the pressure cases' loads (docs/studies.md, stability map);
- the load ramp (:func:`choose_ramp`).

The choice, the figures and the reason are recorded in summary.json.

The same analysis tells whether the set-up's sizes and moduli look consistent
(:func:`scale_warnings`, a one-line warning, never an error): e.g. moduli in Pa where the
loads are in MPa, or the reverse, make that analysis' displacements a millionth of the domain
or its strains a thousand and more.
"""
from __future__ import annotations

import numpy as np

from .case import build_problem
from .derive import derive_settings
from .initial import initial_design
from .parallel import largest as rank_max
from .parallel import total, union
from .physics.materials import green_lagrange
from .physics.quadrature import integration_rules

STRAIN_THRESHOLD = 0.01


def strain_field(mech):
    """The Frobenius norm of the Green–Lagrange strain of ``mech.u`` (a CoefficientFunction)."""
    from ngsolve import Grad, InnerProduct, sqrt

    E = green_lagrange(Grad(mech.u))
    return sqrt(InnerProduct(E, E))


def material_strain(mech, q: float = 0.99) -> tuple[float, float]:
    """``(s, largest)``: the strain ``s`` that a fraction ``q`` of the material stays below (the
    measure ``ρ̄ dx`` of the first design field, at the mechanics' quadrature points), and the
    largest strain at a point with ρ̄ >= 0.5 (0 if there is none).  On a distributed mesh
    over every rank's part (:mod:`pacto_ng.parallel`)."""
    from ngsolve import VOL, IfPos, Integrate, Parameter

    mesh = mech.mesh
    eps, rho = strain_field(mech), mech.fields[0].gf
    pts = mesh.MapToAllElements(mech.rules, VOL)
    e_pts = np.asarray(eps(pts)).ravel()
    r_pts = np.asarray(rho(pts)).ravel()
    largest = max(rank_max(mesh, e_pts[r_pts >= 0.5]), 0.0)
    material = total(mesh, Integrate(rho * mech.DX, mesh))
    if not material > 0:
        return 0.0, largest
    t = Parameter(0.0)
    above = rho * IfPos(eps - t, 1.0, 0.0) * mech.DX

    def share_above(value):
        t.Set(value)
        return total(mesh, Integrate(above, mesh)) / material

    cand = union(mesh, e_pts[r_pts > 0])  # the answer is one of the points' strains
    lo, hi = 0, len(cand) - 1
    while lo < hi:  # the smallest candidate with at most 1 - q of the material above it
        mid = (lo + hi) // 2
        if share_above(cand[mid]) <= 1.0 - q:
            hi = mid
        else:
            lo = mid + 1
    return float(cand[lo]), largest


#: the linear strain per iteration of a chosen load ramp: the first iteration's analysis is
#: within the small-strain regime, and each iteration adds at most that much (measured,
#: docs/studies.md "Extreme pressures at defaults")
RAMP_STRAIN = STRAIN_THRESHOLD


def choose_ramp(strain: float, schedule, iterations: int) -> tuple[int, str]:
    """``(n, reason)``: the load ramp for a nonlinear run whose full load strains the material
    by ``strain`` in a linear analysis: ``ceil(strain / RAMP_STRAIN)`` iterations, none below
    ``RAMP_STRAIN``, ending no later than the penalty and β continuation (so that the ramp
    never delays the convergence test, which waits for that continuation anyway), or than half
    the iterations where there is none, and before the run's last iteration (a short run ends
    at its full load)."""
    want = int(np.ceil(strain / RAMP_STRAIN - 1e-12))
    if want <= 1:
        return 0, (f"material strain of the first linear analysis {strain:.3g} < {RAMP_STRAIN:g}: "
                   f"full load from the first iteration")
    end = schedule.final_at() or iterations // 2
    n = min(want, end, iterations - 1)
    why = (f"material strain of the first linear analysis {strain:.3g}, {RAMP_STRAIN:g} per "
           f"iteration: {want} iterations")
    if n <= 1:
        return 0, why + f", but a run of {iterations} iteration(s) has no room for a ramp"
    if n < want:
        why += (", cut to before the last iteration" if n == iterations - 1 else
                ", cut to where the penalty and beta continuation ends" if schedule.final_at()
                else ", cut to half the iterations")
    return n, why


def displacement_ratio(mech) -> float:
    """The largest displacement ``max |u|`` at the points of the degree-``2 order`` rule on
    ``mech``'s elements (void included) over the domain's size, the largest side of the mesh's
    bounding box.  On a distributed mesh over every rank's part."""
    from ngsolve import VOL

    mesh = mech.mesh
    points = mesh.MapToAllElements(integration_rules(2 * mech.order), VOL)
    u = np.asarray(mech.u(points)).reshape(-1, mesh.dim)
    u_max = max(rank_max(mesh, np.linalg.norm(u, axis=1)), 0.0)
    pts = np.array([v.point for v in mesh.vertices]).reshape(-1, mesh.dim)
    hi = [rank_max(mesh, pts[:, a]) for a in range(mesh.dim)]
    lo = [-rank_max(mesh, -pts[:, a]) for a in range(mesh.dim)]
    size = max(h - lo_a for h, lo_a in zip(hi, lo))
    return u_max / size if size > 0 else 0.0


def first_linear_analysis(case, params, comm=None) -> dict:
    """One linear analysis of the initial design at the full load (on the ranks of ``comm``,
    an mpi4py communicator, as the run itself): ``strain`` and ``largest``
    (:func:`material_strain`) and ``displacement_ratio`` (:func:`displacement_ratio`)."""
    lin = params.replace(model="linear", load_ramp=0, formulation="displacement")
    problem = build_problem(case, lin, comm=comm)
    problem.apply_schedule(*lin.schedule.schedule().values(0))
    problem.evaluate(initial_design(problem), gradients=False)
    strain, largest = material_strain(problem.mech)
    return {"strain": strain, "largest": largest,
            "displacement_ratio": displacement_ratio(problem.mech)}


def first_linear_strain(case, params, comm=None) -> tuple[float, float]:
    """:func:`material_strain` of :func:`first_linear_analysis`."""
    first = first_linear_analysis(case, params, comm)
    return first["strain"], first["largest"]


#: bounds of :func:`scale_warnings`, from the first linear analysis of every built-in case at
#: its defaults and at the loads its documented commands use (measured 2026-12 with
#: :func:`first_linear_analysis`): largest displacement over the domain's size 5.6e-4 (the
#: `pacto new` finger) to 410 (topress: unit modulus, unit pressure), 101 in a nonlinear
#: command (pa-gripper at 1e8 Pa: its passive void); material strain (99th percentile) up to
#: 16 in a nonlinear command (pa-inverter at 1e8 Pa; cantilever at 5e5 N 13) and 1.2e6 in
#: the linear ports of the unit-modulus codes (topress; sorotop 3.5e5, mbb 431).
#: Below this ratio the displacements are lost in the domain's size (a factor 1e6 between
#: moduli and loads, Pa against MPa)
SMALL_DISPLACEMENT = 1e-9
#: a nonlinear model asked to carry more strain than this in the linear analysis, or a
#: displacement larger than this many domain sizes, has moduli and loads that do not match
#: (the linear model is scale-invariant: a unit-modulus set-up is not warned about)
LARGE_STRAIN = 1e3
LARGE_DISPLACEMENT = 1e4


def scale_warnings(first: dict, model: str) -> list[str]:
    """One-line warnings (none, usually) that the set-up's sizes and moduli look
    inconsistent, from :func:`first_linear_analysis` ``first`` and the model the run will use:
    a largest displacement below :data:`SMALL_DISPLACEMENT` of the domain's size (any model);
    for a nonlinear model also a material strain above :data:`LARGE_STRAIN` or a largest
    displacement above :data:`LARGE_DISPLACEMENT` domain sizes."""
    ratio, strain = first["displacement_ratio"], first["strain"]
    where = ("the initial design's linear analysis at the full load gives a largest "
             "displacement of")
    hint = "check the units of the geometry, the moduli (E1, E0) and the load"
    if ratio < SMALL_DISPLACEMENT:
        return [f"{where} {ratio:.2g} of the domain's size (below {SMALL_DISPLACEMENT:g}): "
                f"the load is tiny for these moduli; {hint}"]
    if model == "linear":
        return []
    if strain > LARGE_STRAIN or ratio > LARGE_DISPLACEMENT:
        return [f"{where} {ratio:.3g} times the domain's size and a material strain of "
                f"{strain:.3g}: far beyond what the {model} model can carry; {hint}"]
    return []


def choose(case, params, comm=None, warnings: list | None = None):
    """Resolve ``model=auto`` and ``load_ramp=-1`` from one linear analysis of the initial
    design at the full load (none where only a linear run's ramp is to be chosen), on the
    ranks of ``comm`` (an mpi4py communicator; None: serial).  Returns ``(params,
    model_choice, ramp_choice)``; a record is None where nothing was chosen.  ``warnings``,
    a list, receives :func:`scale_warnings` of that analysis (nothing where none was done)."""
    params = derive_settings(case, params)  # the ramp ends with the derived continuation
    model_choice = ramp_choice = None
    first = None
    if params.model == "auto" or (params.load_ramp < 0 and params.model != "linear"):
        first = first_linear_analysis(case, params, comm)
        strain, largest = first["strain"], first["largest"]
    if params.model == "auto":
        chosen = "linear" if strain < STRAIN_THRESHOLD else "wang"
        reason = (f"Green-Lagrange strain of the first linear analysis (99th percentile of the "
                  f"material) is {strain:.3g} {'<' if chosen == 'linear' else '>='} "
                  f"{STRAIN_THRESHOLD:g}: "
                  + ("small strains, the linear model suffices" if chosen == "linear" else
                     "finite strains: Neo-Hookean where there is material, linear in the void "
                     "(Wang's interpolation)"))
        model_choice = {"requested": "auto", "chosen": chosen, "strain_p99": strain,
                        "strain_max_solid": largest, "threshold": STRAIN_THRESHOLD,
                        "reason": reason}
        params = params.replace(model=chosen)
    if params.load_ramp < 0:
        if params.model == "linear":
            ramp_choice = {"requested": -1, "chosen": 0, "reason": "linear model: the load "
                           "only scales the state, no ramp needed"}
        else:
            n, why = choose_ramp(strain, params.schedule.schedule(), params.iterations)
            ramp_choice = {"requested": -1, "chosen": n, "strain_p99": strain, "reason": why}
        params = params.replace(load_ramp=ramp_choice["chosen"])
    if first is not None and warnings is not None:
        warnings.extend(scale_warnings(first, params.model))
    return params, model_choice, ramp_choice
