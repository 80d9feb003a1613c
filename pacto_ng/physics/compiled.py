"""How the forms Newton assembles in every iteration are built to run fast: their integrands
compiled (:func:`compiled`, to machine code where asked), and in 3D their linearisation by
NGSolve's symbolic derivatives (:func:`symbolic_linearisation`).

Measured 2026-12-06 (1 thread, nothing else running; the median of iterations 1-19 of
history.csv's ``time`` and the run's wall time, 20 iterations; the objectives agree to 1e-12):

| run | tangent | machine code | s / iteration | wall time |
|---|---|---|---|---|
| pneunet-3d, Neo-Hookean (18 473 tetrahedra) | automatic differentiation | yes | 2.24 | 65.4 s |
| | symbolic | yes | **1.78** | 63.9 s |
| | automatic differentiation | no | 3.32 | 87.2 s |
| | symbolic | no | 2.37 | 59.9 s |
| cantilever, Neo-Hookean (5717 triangles) | automatic differentiation | yes | 0.196 | 23.1 s |
| | symbolic | yes | 0.209 | 39.0 s |
| pneunet-silicone, mixed (2400 quadrilaterals) | automatic differentiation | yes | 0.644 | 47.6 s |
| | symbolic | yes | 0.535 | 109.9 s |

(``pacto run CASE --iterations 20 --no-part``, ``--model neohookean`` for the first two.)  The
symbolic tangent makes the compiler's code larger (its run takes 7 s longer on pneunet-3d, 16 s
on the cantilever, 64 s on pneunet-silicone); it pays in 3D, where the tangent of a
tetrahedron's 12 unknowns costs most, and is used there for the displacement formulation.
"""
from __future__ import annotations

import math
import sys
from contextlib import contextmanager

from netgen.meshing import NgException
from ngsolve import ngsglobals


#: a nonlinear model's Newton forms are compiled to machine code (``realcompile`` = -1) where the
#: work they save pays for the compiler: the elements times the Newton iterations expected at
#: least this.  Measured 2026-12-06 (1 thread): compiling took 5.5-7.5 s once per problem
#: built; on cantilever-3d (15,977 tetrahedra, order 1, Neo-Hookean) the tangent's assembly
#: fell from 0.58 to 0.29 s and the residual's from 0.083 to 0.035 s, 21 µs per element and
#: Newton iteration, so that 6 s pays after 3e5; on pneunet-silicone (2400 quadrilaterals,
#: Wang, the mixed formulation) an optimisation iteration of 3 Newton iterations fell from
#: 1.24 to 0.60 s, 89 µs, paying after 7e4
COMPILE_PAYS = 3e5
#: the same where the tangent comes from symbolic derivatives (3D, the displacement
#: formulation: :func:`symbolic_tangent`), whose compiled code is larger: on pneunet-3d (18,473
#: tetrahedra, Neo-Hookean, 1 thread, 2026-12-06) the problem was built in 19.3 s (fixed
#: pressure) and 48.4 s (follower) compiled, 2.6 and 2.2 s not, and an iteration took 1.78 s
#: against 2.37 s, 8 µs per element and Newton iteration: the follower's 46 s pay after 6e6
COMPILE_PAYS_SYMBOLIC = 6e6
#: Newton iterations per optimisation iteration, for that estimate (warm-started at the
#: direct route's tolerance: 4 on the same run)
NEWTON_PER_ITERATION = 4


def element_weight(order: int, dim: int, simplices: bool) -> float:
    """An element's work in a Newton iteration at ``order`` in order-1 elements (the unit of
    :data:`COMPILE_PAYS`): its nodes at ``order`` over its nodes at order 1 (10/4 for an
    order-2 tetrahedron).  Measured 2026-12-08 (cantilever-3d, Neo-Hookean, order 2, 6574
    tetrahedra, iterative route, 1 thread, the median of iterations 1-5 of a run): compiling
    took 26.5 s and an iteration fell from 3.85 to 3.40 s, 17 µs per element and Newton
    iteration (about 4 tangents per iteration) against the 8 µs of order 1: 2.1 order-1
    elements."""
    if simplices:
        return math.comb(order + dim, dim) / (dim + 1)
    return ((order + 1) / 2) ** dim


def symbolic_tangent(dim: int, formulation: str) -> bool:
    """Whether a mechanics block's tangent comes from symbolic derivatives: in 3D with the
    displacement formulation, where it pays (the module's table)."""
    return dim == 3 and formulation == "displacement"


@contextmanager
def symbolic_linearisation(on: bool = True):
    """With ``on``, forms built inside get their tangent (``AssembleLinearization``) from
    symbolic derivatives of their integrands (``Diff``), built once, instead of automatic
    differentiation at every quadrature point: NGSolve's ``symbolic_integrator_uses_diff``,
    read when an integrator is made.  The matrices agree to round-off."""
    before = ngsglobals.symbolic_integrator_uses_diff
    ngsglobals.symbolic_integrator_uses_diff = on or before
    try:
        yield
    finally:
        ngsglobals.symbolic_integrator_uses_diff = before


def compiled(cf, realcompile: bool):
    """``(cf compiled, realcompile)``: to machine code with ``realcompile``, unless the
    compiler behind NGSolve's ``ngscxx`` fails (no C++ compiler on the machine: said once, on
    stderr, and the second value is then False), else as a compiled expression."""
    if realcompile:
        try:
            return cf.Compile(realcompile=True, wait=True), True
        except NgException as err:
            print(f"pacto: warning: the Newton forms are not compiled to machine code ({err}); "
                  f"an optimisation iteration takes about 1.3x longer", file=sys.stderr, flush=True)
    return cf.Compile(), False
