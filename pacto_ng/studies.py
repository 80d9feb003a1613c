"""Script-level analyses that are not optimisations: the C-beam load limit (docs/theory.md §6).

The C-beam (Yoon et al. 2005; Wang et al. 2014 §2; thesis §5.2.1 and App. C) is a 10 x 10 m
square whose C-shaped solid (1 m thick top, bottom and left arms; ``ρ = γ = 1``) surrounds a
void (``ρ = γ = 0``, ``E0 = 1e-9 E1``).  The left edge is clamped; ``f1`` pulls the free end of
the top arm down and ``f2`` the free end of the bottom arm to the right, both times a load
factor ``λ``.  The void elements between the arms are crushed as ``λ`` grows: with a
Neo-Hookean void they invert and Newton stops; the Wang interpolation (thesis eq. 5.1) treats
the void with small-strain theory and carries the C much further.  Thesis (COMSOL, triangles):
Neo-Hookean (f1, f2) = (0.0009, 0.0099) N, Wang (0.0055, 0.0145) N.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .geometries.c_beam import layout as c_beam_layout
from .mesh import netgen_mesh, structured_mesh
from .params import Parameters
from .physics.energy import make_energy
from .physics.loads import PointLoad
from .physics.materials import jacobian
from .physics.mechanics import Mechanics, Supports
from .physics.newton import NewtonSettings, solve_with_continuation
from .physics.quadrature import guard_rules


@dataclass
class CBeamResult:
    """Outcome of :func:`c_beam_limit`.

    ``load_factor`` is the largest ``λ`` at which an equilibrium was found with no inverted
    element in the checked region (the forces are then ``λ (f1, f2)``); ``reason`` says what
    stopped the next increment (Newton, or an inverted element).  ``history`` lists
    ``(λ, Newton iterations)`` and ``steps`` ``(λ, min det F solid, min det F void)`` per
    accepted increment, ``det F`` sampled at the integration points, the vertices, the edge
    midpoints and the centroid of every element.
    """

    model: str
    order: int
    mesh: str
    load_factor: float
    forces: tuple[float, float]
    reached_max: bool
    reason: str
    iterations: int
    tip_displacement: tuple[float, float, float, float]  # (u_x, u_y) at f1, then at f2
    history: list = field(default_factory=list)
    steps: list = field(default_factory=list)
    mechanics: object = None


def c_beam_limit(model: str = "neohookean", *, order: int = 1, mesh: str = "quad",
                 lam_max: float = 20.0, first_step: float = 0.05, resolution: float = 0.01,
                 f1: float = 0.002, f2: float = 0.003, E1: float = 1.0, E0_ratio: float = 1e-9,
                 nu: float = 0.3, thickness: float = 1.0, h: float = 1.0,
                 loads_on: str = "points", line_search: str = "guard",
                 wang_beta: float = 100.0, wang_eta: float = 0.001,
                 stop_at_inversion: bool = True) -> CBeamResult:
    """Largest load factor ``λ`` the C-beam reaches before Newton fails or an element inverts.

    The load is ramped from 0 towards ``lam_max`` by :func:`~pacto_ng.physics.newton.
    solve_with_continuation` (first increment ``first_step``, growing after easy steps, halved
    after a failed one down to ``resolution``, so ``λ`` is resolved to ``resolution``).  An
    increment fails when

    * Newton does not converge in 30 iterations, or every step length would make the guard
      ``det(I + γ∇u) <= 0`` at an integration point (``γ = 1`` for the plain models), or
    * (``stop_at_inversion``) the converged state has an inverted element: ``det F <= 0`` at a
      vertex, edge midpoint, centroid or integration point of an element of the checked region
      — every element for the plain models, the solid (γ > 0) for ``wang``, whose void is
      linear and may invert harmlessly.  The guard alone sees only integration points, where
      a bilinear or quadratic element can still be folded at its corners.

    Measured (h = 1, λ_max = 12, first step 0.05): Neo-Hookean 1.40 (Q1), 0.66 (Q2), 0.55
    (P2 triangles); Wang reaches λ_max with every element (and λ = 500).  The Neo-Hookean
    value depends on the load path (first step 0.01-0.2, λ_max 12 or 20, h 0.37-1: 0.44-1.52),
    the crushed void having many near-equivalent configurations.  With P1 triangles (constant
    det F) no element inverts and Neo-Hookean also reaches λ_max.  With the guard alone
    (``stop_at_inversion=False``) Neo-Hookean goes on to λ = 312 (Q1), 51 (Q2), 34 (P2
    triangles) with folded void elements.  The thesis's Neo-Hookean limit f1 = 0.0009 N is
    λ = 0.45.
    Parameters
    ----------
    model : {"linear", "gnl", "neohookean", "wang"}
    order : int
        Displacement order.
    mesh : {"quad", "trig"}
        Structured ``h``-sized quadrilaterals (10 x 10 at h = 1) or Netgen triangles of size h.
    lam_max, first_step, resolution : float
        Target, first increment and smallest increment of the load factor.
    f1, f2 : float
        Base forces (N): ``f1`` downward at the top arm's end, ``f2`` rightward at the bottom's.
    E0_ratio : float
        ``E0 / E1`` of the void.
    wang_beta, wang_eta : float
        ``β1``, ``η1`` of eq. 5.2 (γ is 1 in the C and 0 in the void to round-off for any of them).
    """
    from ngsolve import Parameter

    layout = c_beam_layout(loads_on=loads_on)
    msh = _c_beam_mesh(layout, mesh, h)
    material = Parameters(model=model, E1=E1, E0=E0_ratio * E1, nu=nu, plane="strain",
                          wang_beta=wang_beta, wang_eta=wang_eta)
    energy, guard, linear = make_energy(material, Parameter(3.0))
    settings = NewtonSettings(rtol=1e-10, max_iter=30, initial_increment=first_step / lam_max,
                              min_increment=resolution / lam_max, max_steps=2000,
                              line_search=line_search)
    mech = Mechanics(msh, order=order, energy=energy, supports=Supports(clamp=("fixed",)),
                     loads=(PointLoad("f1", (0.0, -f1)), PointLoad("f2", (f2, 0.0))),
                     thickness=thickness, guard=guard, linear=linear, newton=settings)
    solid = np.array([el.mat != "void" for el in msh.Elements()])
    mech.set_fields(solid.astype(float))
    steps = []
    accept = _inversion_check(mech, solid, mesh, model == "wang", stop_at_inversion, steps)
    res = solve_with_continuation(mech, mech.state_vector, lam_max, settings, warm=False,
                                  linear=linear, accept=accept)
    lam = res.load_reached
    reason = f"reached lam_max = {lam_max:g}" if res.converged else res.reason
    u1 = mech.u(msh(layout.width, layout.height))
    u2 = mech.u(msh(layout.width, 0.0))
    return CBeamResult(model, order, mesh, lam, (lam * f1, lam * f2), res.converged, reason,
                       res.iterations, (u1[0], u1[1], u2[0], u2[1]), res.history, steps, mech)


def _c_beam_mesh(layout, mesh: str, h: float):
    """The C-beam's square as structured ``h``-sized quadrilaterals (``quad``) or Netgen
    triangles of size ``h`` (``trig``)."""
    if mesh == "quad":
        n = int(round(layout.width / h))
        return structured_mesh(layout, n, n)
    if mesh == "trig":
        return netgen_mesh(layout, h)
    raise ValueError("mesh must be 'quad' or 'trig'")


def _inversion_check(mech, solid, mesh: str, wang: bool, stop_at_inversion: bool, steps: list):
    """The ``accept`` of :func:`~pacto_ng.physics.newton.solve_with_continuation`: a converged
    increment is refused (``stop_at_inversion``) when ``det F <= 0`` anywhere in the checked
    region (the solid for ``wang``, else every element), sampled densely (integration points,
    vertices, edge midpoints and centroid); an accepted one appends ``(λ, min det F solid,
    min det F void)`` to ``steps``."""
    from ngsolve import QUAD, TRIG, VOL, Grad

    rules = guard_rules(mech.rules)
    Jcf = jacobian(Grad(mech.u))
    pts = mech.mesh.MapToAllElements(rules, VOL)
    per_el = len(rules[QUAD if mesh == "quad" else TRIG].points)
    solid_pts = np.repeat(solid, per_el)
    checked = solid_pts if wang else np.ones_like(solid_pts)

    def accept(load, u):
        mech.state_vector.data = u
        vals = np.asarray(Jcf(pts)).ravel()
        if stop_at_inversion and float(vals[checked].min()) <= 0.0:
            where = "of the solid " if wang else ""
            return f"an element {where}inverted (det F <= 0 at a vertex or edge midpoint)"
        steps.append((load, float(vals[solid_pts].min()), float(vals[~solid_pts].min())))
        return ""

    return accept
