"""Neo-Hookean re-analysis of a remeshed design over a sweep of pressures (thesis §6.1.1–6.1.2).

Three loads, each in plane strain with thickness ``t`` on the remeshed solid (reference
configuration Ω0, boundary ``pressure`` with outward unit normal N0 and unit tangent T):

``fixed``
    boundary pressure, deformation independent: the residual gains ``t ∫ P N0 · v dA0``
    (a potential term, symmetric tangent);
``follower``
    boundary pressure following the deformation: ``t ∫ P J F⁻ᵀ N0 · v dA0``.  In 2D
    ``J F⁻ᵀ N0 = Rot(F T)`` with ``Rot(w) = (w₁, -w₀)`` and ``F T = T + (∇u) T``, which only
    needs the tangential derivative ``Grad(u).Trace()`` available on a boundary.  The term is
    not the derivative of a potential: it enters :class:`~pacto_ng.physics.mechanics.Mechanics`
    as a residual term, and ``AssembleLinearization`` supplies its load stiffness (an
    unsymmetric tangent, solved with UMFPACK);
``darcy``
    the Darcy pressure of the thresholded design as a fixed body load ``t ∫ -∇p · v dΩ0``
    (docs/theory.md §4), given as a callable ``body(mesh) -> CF`` (see
    :func:`pressure_body_force`), scaled linearly with the swept inlet pressure.

With ``N0`` the outward normal of the solid, ``+P N0`` in the residual is the traction
``-P N0``: the pressure pushes into the solid.  Each pressure of a sweep is solved by Newton with
adaptive load steps (:mod:`pacto_ng.physics.newton`), warm-started from the previous pressure's
equilibrium.  The output is read at one or several output ports (named points), as the
optimisation defines it (:class:`~pacto_ng.physics.loads.Port`): ``Δ = Σ_k w_k d_k · u(x_k)``,
each port with its output spring ``k_k/2 (d̂_k · u)²``; every port's own ``d_k · u(x_k)`` is
recorded beside Δ.
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from ..physics.energy import declare
from ..physics.equilibrium import NewtonFailure
from ..physics.loads import Port
from ..physics.materials import jacobian, neohookean_energy
from ..physics.mechanics import Mechanics, Supports
from ..physics.newton import NewtonSettings
from .boundary import named_points
from .materials import modulus_cf
from .part_analysis import Sweep, SweepPoint  # noqa: F401  (the results, defined there)

KINDS = ("fixed", "follower", "darcy")


def output_ports(output) -> tuple[Port, ...]:
    """The output ports of ``output``: one :class:`~pacto_ng.physics.loads.Port` or several (the
    forms ``Setup(port=...)`` takes), each on a point of its own; ValueError otherwise."""
    ports = (output,) if isinstance(output, Port) else tuple(output)
    if not ports or not all(isinstance(p, Port) for p in ports):
        raise ValueError("output: give a Port or a non-empty tuple of Ports")
    regions = [p.region for p in ports]
    twice = sorted({r for r in regions if regions.count(r) > 1})
    if twice:
        raise ValueError(f"two output ports on '{twice[0]}': the re-analysis records every "
                         f"port's value by its point, one port to a point")
    return ports


# ---------------------------------------------------------------------------------------
def outward_sign(mesh):
    """±1 per boundary edge so that ``sign * specialcf.normal(2)`` points out of the body.

    NGSolve orients a boundary normal by the edge's own orientation, which on the boundary of a
    hole points *into* the body (checked: ``∫ n·x ds`` over a ring quarter gave 2.5π instead of
    2|Ω| = 1.5π).  The sign is decided per edge by comparing ``Rot(∫ T ds)`` (NGSolve's normal
    direction, as ``n = Rot(T)``) with the direction from the neighbouring element's centroid to
    the edge midpoint; it is returned as a GridFunction on ``FacetFESpace(mesh, order=0)``.
    """
    from ngsolve import BND, FacetFESpace, GridFunction, LinearForm, ds, specialcf

    fes = FacetFESpace(mesh, order=0)
    q = fes.TestFunction()
    T = specialcf.tangential(2)
    tx = LinearForm(T[0] * q * ds).Assemble().vec.FV().NumPy()
    ty = LinearForm(T[1] * q * ds).Assemble().vec.FV().NumPy()
    sign = GridFunction(fes)
    vals = sign.vec.FV().NumPy()
    for el in mesh.Elements(BND):
        d = fes.GetDofNrs(el)[0]
        vol = mesh[el.edges[0]].elements[0]
        cen = np.mean([mesh[v].point for v in mesh[vol].vertices], axis=0)
        mid = np.mean([mesh[v].point for v in el.vertices], axis=0)
        vals[d] = 1.0 if ty[d] * (mid[0] - cen[0]) - tx[d] * (mid[1] - cen[1]) > 0 else -1.0
    return sign


class FixedBoundaryPressure:
    """Boundary pressure ``P`` on ``boundary`` that does not follow the deformation.

    Used as a load of :class:`Mechanics`: its work ``W(u) = -t ∫ P N0 · u dA0`` enters the
    potential as ``-s W(u)`` (``s`` the load factor), so the residual gains ``s t ∫ P N0 · v``.
    """

    def __init__(self, boundary: str, pressure, thickness: float):
        self.boundary, self.pressure, self.thickness = boundary, pressure, float(thickness)

    def work(self, mesh, u, scale=1.0):
        from ngsolve import ds, specialcf

        n = outward_sign(mesh) * specialcf.normal(2)
        return (scale * (-self.thickness) * self.pressure * (n * u)) * ds(self.boundary)


def follower_pressure_terms(mesh, boundary: str, pressure, thickness: float) -> Callable:
    """Residual terms ``(u, v, load) -> s t ∫ P J F⁻ᵀ N0 · v dA0`` for :class:`Mechanics`.

    Uses ``J F⁻ᵀ N0 = Rot(F T)`` (2D), ``F T = T + Grad(u).Trace() T``, with the tangent
    oriented by :func:`outward_sign` so that ``Rot(T) = N0`` points out of the body.
    """
    from ngsolve import CF, Grad, ds, specialcf

    sign = outward_sign(mesh)

    def terms(u, v, load):
        T = sign * specialcf.tangential(2)
        FT = T + Grad(u).Trace() * T
        return (load * thickness * pressure * (CF((FT[1], -FT[0])) * v)) * ds(boundary)

    return terms


def pressure_body_force(p, order: int = 1) -> Callable:
    """A body-force callable ``mesh -> -∇p`` for the ``darcy`` analysis.

    ``p`` is the Darcy pressure of the thresholded design (a GridFunction or CF on the source
    mesh, e.g. the output of :class:`~pacto_ng.physics.darcy.DarcyPressure` at inlet pressure
    ``P_in``, which the analysis then takes as ``body_pressure``); it is interpolated onto an
    H1 space of ``order`` on the new mesh (NGSolve's ``Set`` evaluates a field of another mesh
    by point search) and differentiated there.
    """

    def body(mesh):
        from ngsolve import H1, Grad, GridFunction

        gp = GridFunction(H1(mesh, order=order))
        gp.Set(p)
        return -Grad(gp)

    return body


class Reanalysis:
    """One Neo-Hookean plane-strain analysis of a remeshed solid under one kind of pressure.

    Parameters
    ----------
    mesh : ngsolve.Mesh
        The remeshed solid (see :func:`~pacto_ng.post.remesh.remesh`).
    kind : {"fixed", "follower", "darcy"}
    E : float or dict
        Young's modulus (Pa) of the solid, or ``{material: E}`` for a mesh of several
        materials (two-material parts: ``{"soft": E1, "stiff": E2}``, :mod:`.materials`).
    nu : float
        Poisson's ratio.
    thickness : float
        Out-of-plane thickness (m).
    supports : Supports
        Dirichlet conditions by boundary / point name.
    output : Port or tuple of Port
        The output port(s) at named points of ``mesh``: Δ = Σ weight · direction · u, each
        port with its spring.
    order : int
        Order of the displacement space.
    boundary : str
        The wetted boundary (``fixed`` and ``follower``).
    body : callable ``mesh -> CF``, optional
        Body force per unit volume at inlet pressure ``body_pressure`` (``darcy``).
    body_pressure : float
        The inlet pressure ``body`` belongs to; the load scales with ``P / body_pressure``.
    newton : NewtonSettings
    formulation : str
        ``auto`` (the mixed formulation from ν >= 0.45 at order >= 2,
        :func:`~pacto_ng.physics.mixed.formulation_for`), ``displacement`` or ``mixed``;
        :attr:`formulation` is the one used.
    """

    def __init__(self, mesh, kind: str, *, E: float | dict, nu: float, thickness: float,
                 supports: Supports, output: Port | tuple[Port, ...], order: int = 2,
                 boundary: str = "pressure", body: Callable | None = None,
                 body_pressure: float = 1.0, newton: NewtonSettings = NewtonSettings(),
                 formulation: str = "auto"):
        from ngsolve import QUAD, TRIG, VOL, Grad, InnerProduct, IntegrationRule, Parameter

        if kind not in KINDS:
            raise ValueError(f"kind must be one of {', '.join(KINDS)}, not {kind!r}")
        if kind in ("fixed", "follower") and boundary not in mesh.GetBoundaries():
            raise ValueError(f"the mesh has no '{boundary}' boundary to apply the pressure on")
        if kind == "darcy" and body is None:
            raise ValueError("the darcy analysis needs a body-force callable "
                             "(see pressure_body_force)")
        self.mesh, self.kind, self.ports = mesh, kind, output_ports(output)
        self.E = {k: float(v) for k, v in E.items()} if isinstance(E, dict) else float(E)
        self.nu, self.thickness = float(nu), float(thickness)
        modulus = modulus_cf(mesh, self.E)
        self.P = Parameter(0.0)
        points = named_points(mesh)
        for port in self.ports:
            if port.region not in points:
                raise ValueError(f"the mesh has no named point '{port.region}'")
        xy = np.array([points[port.region][:2] for port in self.ports], dtype=float)
        self._port_points = mesh(xy[:, 0].copy(), xy[:, 1].copy())
        self._directions = np.array([port.direction for port in self.ports], dtype=float)
        self._weights = np.array([port.weight for port in self.ports], dtype=float)
        springs = tuple(sp for port in self.ports for sp in port.springs())
        loads, terms, bodyf = (), None, None
        if kind == "fixed":
            loads = (FixedBoundaryPressure(boundary, self.P, thickness),)
        elif kind == "follower":
            terms = follower_pressure_terms(mesh, boundary, self.P, thickness)
        else:
            b = body(mesh)
            self.body_pressure = float(body_pressure)
            bodyf = lambda u, coeffs: (self.P / self.body_pressure) * InnerProduct(b, u)
        energy = declare(lambda G, coeffs: neohookean_energy(G, modulus, self.nu, "strain"),
                         reads=(), stress_free=True)
        from ..physics.mixed import formulation_for, has_simplices

        self.formulation = formulation_for(formulation, model="neohookean", nu=self.nu,
                                           plane="strain", dim=mesh.dim, order=order,
                                           simplices=has_simplices(mesh))
        self.mech = Mechanics(mesh, order=order, energy=energy, fields=(), supports=supports,
                              loads=loads, springs=springs, body=bodyf, thickness=thickness,
                              guard=lambda G, coeffs: jacobian(G), newton=newton,
                              residual_terms=terms, formulation=self.formulation)
        rule = {TRIG: IntegrationRule(TRIG, 2 * order), QUAD: IntegrationRule(QUAD, 2 * order)}
        self._pts = mesh.MapToAllElements(rule, VOL)
        self._J = jacobian(Grad(self.mech.gfu))
        coords = np.array([mesh[v].point for v in mesh.vertices])
        self._vertices = mesh(coords[:, 0].copy(), coords[:, 1].copy())

    def solve(self, pressure: float) -> SweepPoint:
        """Equilibrium at ``pressure`` (warm-started from the previous converged state)."""
        self.P.Set(float(pressure))
        # The pressure is a Parameter inside the load, outside Mechanics' load factor: the norm
        # of the unit load that Mechanics caches for fixed loads (the reference of Newton's
        # relative tolerance) belongs to the previous pressure.  Without this reset a sweep
        # 1 -> 10 -> 100 Pa judged the residual at 100 Pa against the load at 1 Pa, asked for
        # a 100x smaller residual than rtol and failed at the round-off floor.
        self.mech.load_changed()
        try:
            self.mech.forward()
            ok = True
        except NewtonFailure:
            ok = False
        res = self.mech.result
        if not ok:
            return self._failed(pressure, res.iterations, float(res.load_reached))
        along, max_u = self._read(self.mech.gfu)
        return SweepPoint(float(pressure), float(self._weights @ along), max_u,
                          float(np.min(self._J(self._pts))), int(res.iterations), True, 1.0,
                          tuple(map(float, along)))

    def _read(self, gfu):
        """``(d_k·u(x_k) of every port, largest |u| over the vertices)``."""
        u_ports = np.asarray(gfu(self._port_points)).reshape(len(self.ports), -1)
        along = np.einsum("ij,ij->i", self._directions, u_ports)
        u_v = np.asarray(gfu(self._vertices)).reshape(-1, 2)
        return along, float(np.max(np.linalg.norm(u_v, axis=1)))

    def _failed(self, pressure, iterations, load_reached) -> SweepPoint:
        return SweepPoint(float(pressure), np.nan, np.nan, np.nan, int(iterations), False,
                          load_reached, (np.nan,) * len(self.ports))

    def sweep(self, pressures, *, stop_on_failure: bool = True) -> Sweep:
        """Solve at every pressure in turn (give them in increasing order).

        After a failure the remaining pressures are recorded as not converged without being
        attempted (``stop_on_failure``), since a larger pressure starts from further away.
        """
        from ..threads import compute

        out = Sweep(self.kind, [], self)
        failed = False
        with compute():
            for P in pressures:
                if failed and stop_on_failure:
                    out.points.append(self._failed(P, 0, 0.0))
                    out.states.append(None)
                    continue
                pt = self.solve(P)
                out.points.append(pt)
                out.states.append(self.mech.gfu.vec.FV().NumPy().copy() if pt.converged else None)
                failed = not pt.converged
        return out


def analyse(mesh, pressures, *, kinds=("fixed", "follower"), **kwargs) -> dict:
    """Sweep ``pressures`` with every analysis in ``kinds``; returns ``{kind: Sweep}``.

    ``kwargs`` go to :class:`Reanalysis` (``E``, ``nu``, ``thickness``, ``supports``,
    ``output``, ``order``, ``boundary``, ``body``, ``body_pressure``, ``newton``).
    """
    return {k: Reanalysis(mesh, k, **kwargs).sweep(pressures) for k in kinds}
