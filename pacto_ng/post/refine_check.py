"""``pacto refine RUN --check-gradients``: the refinement's shape gradients checked against
central finite differences on the run's own part.

The part is made and loaded exactly as ``pacto refine RUN`` makes and loads it
(:func:`~.refine_run.refinement`).  For ``directions`` smooth directions ``V`` of the
boundary's motion (the Riesz representative (:class:`~pacto_ng.shape.riesz.RieszMap`) of a
random vector with a fixed seed: smooth, zero on the clamp, the ports and across symmetry
lines, as every refinement step is), scaled to a largest vertex motion ``h`` (:data:`STEP`
times the part's element size), each measure ``J`` the refinement uses (the output Δ, the
volume, and for a mechanism run the ratio Δ/SE) is compared:

    adjoint:  dJ · V          central difference:  (J(+V) - J(-V)) / 2

with the relative error ``|a - c| / max(|a|, |c|)``.  The check passes when every error is at
most ``tol`` (default :data:`TOL`, the bound the project's tests hold the shape gradient to);
the exit code is 0 then, 1 otherwise.  Nothing is written.
"""
from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..physics.equilibrium import NewtonFailure
from ..shape import RieszMap, volume, volume_integrals
from .finish import say
from .refine_setup import Loading, part_size, refinement, shape_response
from .runs import load_run

#: the directions checked when ``--directions`` is not given
DIRECTIONS = 3
#: the largest vertex motion of a checked direction, in the part's element sizes
STEP = 1e-3
#: the largest relative error accepted
TOL = 1e-5
#: the seed of the random directions (the same directions on every call)
SEED = 0


def check_refine_gradients(folder, *, directions: int = DIRECTIONS, tol: float = TOL,
                           quiet: bool = False, loading: Loading = Loading()) -> int:
    """The module's check on the finished run ``folder``; returns the exit code (0 when
    every relative error is at most ``tol``, else 1); bad input is an InputError."""
    if directions < 1:
        raise InputError(f"--directions: must be 1 or more, got {directions}")
    if not tol > 0:
        raise InputError(f"--tol: must be positive, got {tol}")
    run = load_run(folder, "refine")
    part, job = refinement(run, quiet, f"the shape gradients checked in {directions} "
                                       f"directions", loading)
    response, space = shape_response(part.mesh, job)
    names = ("delta", "volume") + (("ratio",) if job.hold_ratio else ())
    riesz = RieszMap(space, alpha=1.0 / part_size(part.mesh) ** 2)
    rng = np.random.default_rng(SEED)
    worst = 0.0
    for k in range(1, directions + 1):
        theta = riesz(rng.standard_normal(space.ndof))
        theta *= STEP * job.maxh / float(np.max(np.abs(theta)))
        for name, (adjoint, central) in _compare(response, space, theta, names).items():
            error = abs(adjoint - central) / max(abs(adjoint), abs(central), 1e-300)
            worst = max(worst, error)
            say(quiet, f"  direction {k}, {LABELS[name]}: adjoint {adjoint:.10g}, central "
                       f"difference {central:.10g}, relative error {error:.2g}")
    ok = worst <= tol
    print(f"refine {run.path} --check-gradients: the largest relative error {worst:.2g} "
          f"({'within' if ok else 'above'} {tol:g}) over {directions} direction"
          f"{'s' if directions > 1 else ''} and {', '.join(LABELS[n] for n in names)}",
          flush=True)
    return 0 if ok else 1


#: how each measure is named in the lines
LABELS = {"delta": "Δ", "volume": "volume", "ratio": "Δ/SE"}


def _compare(response, space, theta, names) -> dict:
    """``{name: (dJ · θ, (J(+θ) - J(-θ)) / 2)}`` at the part's starting shape."""
    thickness = response.thickness
    try:
        space.set(np.zeros(space.ndof))
        response.solve()
        adjoint = {n: float(space.derivative(volume_integrals(thickness)) @ theta)
                   if n == "volume" else float(response.gradient(space, n) @ theta)
                   for n in names}
        sides = []
        for sign in (1.0, -1.0):
            space.set(sign * theta)
            response.solve()
            sides.append({n: volume(space.mesh, thickness) if n == "volume"
                          else response.value(n) for n in names})
    except NewtonFailure as err:
        raise InputError(f"refine: the part has no equilibrium at the run's load ({err})") \
            from None
    finally:
        space.set(np.zeros(space.ndof))
    return {n: (adjoint[n], 0.5 * (sides[0][n] - sides[1][n])) for n in names}

