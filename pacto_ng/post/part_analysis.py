"""One analysis of a part -- a body-fitted mesh of the solid only -- with the run's own material
law, under a wall pressure that is fixed or follows the deformation, in 2D and 3D alike.

The part (:func:`~pacto_ng.post.remesh.remesh` in 2D, :func:`~pacto_ng.post.remesh3d.
remesh_part` in 3D, or a case's own mesh as built: :mod:`~pacto_ng.post.as_built`) is the
reference configuration Ω0 with boundary names: ``pressure`` (the wetted chamber walls) and
the case's own (``fixed``, ``symmetry``, ``inlet``, ``free``, ...) and named points.  The
dimension ``d`` is the mesh's; in 2D every integral carries the thickness ``t``
(``params.thickness``; ``t = 1`` in 3D), in plane strain or stress (``params.plane``).

Material.  The energy is the run's, built by :func:`~pacto_ng.physics.energy.make_energy` from
the run's :class:`~pacto_ng.params.Parameters` (model, E0, E1, E2, ν, plane, material preset,
Wang parameters) on element fields that describe solid material everywhere
(:func:`solid_fields`):

* one material (no element material named ``stiff``): ``ρ̄ = 1`` on every element, so SIMP
  gives ``E = E0 + 1^p (E1 - E0) = E1`` (Bendsøe and Sigmund 2003, *Topology optimization*,
  eq. 1.3; thesis eq. A.23);
* a part with a region named ``stiff`` (a two-material design's ``soft`` and ``stiff``,
  :mod:`.materials`; an as-built case's faces or solids named ``stiff`` beside any others):
  ``ρ̄1 = 1`` and ``ρ̄2 = 1`` on ``stiff``, 0 elsewhere, so the two-material SIMP (thesis
  eq. 6.1) ``E = (1-ρ̄1^p) E0 + ρ̄1^p [(1-ρ̄2^p) E1 + ρ̄2^p E2]`` gives exactly E2 on ``stiff``
  and E1 on every other region.  A rubber law (a preset's) scales with E as every law does:
  ``stiff`` has the same law, E2/E1 times stiffer.

For the Wang model (Wang, Lazarov, Sigmund and Jensen 2014, *Comput. Methods Appl. Mech.
Engrg.* 277; thesis eqs 5.1-5.2) ``γ = H(ρ̄^p; η1, β1) = H(1) = 1`` (exactly; in floating point
to one ulp, e.g. 1 - 1.1e-16 at β1 = 500, η1 = 0.01), so ``φ_W = φ_H(γ∇u) - φ_L(γ∇u) +
φ_L(∇u) = φ_H(∇u)``: the part obeys the hyperelastic law, which is what the Wang model says of
solid material (unless the run prescribed a constant γ with ``wang_gamma``, which then applies
here too).  The displacement or mixed formulation is
:func:`~pacto_ng.physics.mixed.formulation_for` of the run's setting.

Loads (:mod:`pacto_ng.physics.walls`): the wall pressure ``fixed`` or ``follower`` on the
wetted wall ``Γp`` (``boundary``), or the ``darcy`` body force of a design's pressure field,
with the pressure ``P`` as the load factor of :class:`~pacto_ng.physics.mechanics.Mechanics`.
With ``contact``, the part's walls are in frictionless self-contact
(:mod:`pacto_ng.physics.contact`).

Output.  The ports are read with :meth:`~pacto_ng.physics.loads.Port.functional`, the
functional of the optimisation's output (a named point's value, or the mean over a named edge
or face): ``Δ = Σ_k w_k d_k · u`` over the ports, each port's own ``d_k · u`` and its
displacement vector (the value at the point, or the mean over the edge or face), so that a
caller can see a port move more in a direction the objective leaves free.  Each port's spring
(:meth:`~pacto_ng.physics.loads.Port.springs`) and any extra :class:`~pacto_ng.physics.loads.
Spring` act on the part.  Also recorded: the largest ``|u|`` over the vertices and the smallest
``det(I + ∇u)`` over the quadrature points of the forms (in 2D of the in-plane deformation; of
the displacement, not of the mixed formulation's modified gradient).
"""
from __future__ import annotations

import dataclasses
import time
from typing import Callable

import numpy as np
from ngsolve import VOL, Grad, InnerProduct, LinearForm, Parameter

from ..errors import InputError
from ..physics.compiled import element_weight, symbolic_tangent
from ..physics.contact import SelfContact
from ..physics.energy import make_energy
from ..physics.equilibrium import NewtonFailure
from ..physics.loads import Port, Spring
from ..physics.materials import jacobian
from ..physics.mechanics import Mechanics, Supports
from ..physics.mixed import formulation_for, has_simplices
from ..physics.walls import (WallPressure, follower_terms, held_planes_origin, outward_normal,
                             volume_change)
from ..threads import compute
from .materials import STIFF
from .past_peak import past_peak
from .sweep_result import Sweep, SweepPoint

KINDS = ("fixed", "follower", "darcy")
#: self-contact: the penalty stiffness in units of E1 / h (an overlap of 5e-4 h at a contact
#: pressure of E1), and the distance within which pairs are sought, in element sizes
CONTACT_PENALTY, CONTACT_REACH = 1e3, 3.0
#: without contact, Newton's load ramp gives up once its increment falls below this share of
#: the pressure: the path past a pressure maximum takes over (:mod:`.past_peak`)
RAMP_FLOOR = 1.0 / 64


def solid_fields(mesh) -> dict:
    """The element fields of a solid part (numpy, one value per element in NGSolve's order):
    ``{"rho_bar": 1}``, or for a part with an element material named ``stiff``
    ``{"rho_bar1": 1, "rho_bar2": 1 on stiff, 0 on every other material}`` (see the module:
    E2 on ``stiff``, E1 elsewhere)."""
    mats = [el.mat for el in mesh.Elements(VOL)]
    ones = np.ones(len(mats))
    if STIFF not in mats:
        return {"rho_bar": ones}
    return {"rho_bar1": ones, "rho_bar2": np.array([m == STIFF for m in mats], dtype=float)}


#: Newton iterations of a sweep, for the compiler's estimate (compiled.COMPILE_PAYS): five
#: pressures at 3-4 each (pneunet-3d's part, Neo-Hookean, 2026-12-06)
SWEEP_NEWTON = 20

class PartAnalysis:
    """One analysis of a part with the run's material law (see the module).

    Parameters
    ----------
    mesh : ngsolve.Mesh
        The part: 2D (plane strain or stress, thickness ``params.thickness``) or 3D.
    kind : {"fixed", "follower", "darcy"}
        The load: the wall pressure, fixed or follower, or the Darcy body force (``body``).
    params : pacto_ng.params.Parameters
        The run's parameters: model, E0, E1, E2, ν, plane, thickness, material, Wang's β1, η1
        (and γ), penal, formulation, order, Newton's settings, realcompile (-1: where it pays).
    supports : Supports
        Dirichlet conditions by name (a name the part lacks: ValueError from Mechanics).
    ports : Port or tuple of Port
        The output ports (named points, edges or faces).
    springs : tuple of Spring
        Springs beyond the ports' own.
    order : int, optional
        Displacement order (default ``params.order``, else 1).
    boundary : str
        The wetted wall (``fixed`` and ``follower``).
    body : callable ``mesh -> CF``, optional
        ``darcy``: the body force per unit volume at inlet pressure ``body_pressure``
        (:func:`pressure_body_force`); the load scales with ``P / body_pressure``.
    body_pressure : float, optional
        The inlet pressure ``body`` belongs to.
    contact : tuple of str, optional
        Boundaries in frictionless self-contact (:class:`~pacto_ng.physics.contact.
        SelfContact`, the displacement formulation only), with the penalty stiffness
        ``contact_penalty`` E1 / h (h the part's mean element size) and pairs sought within
        :data:`CONTACT_REACH` h.
    chamber : bool
        The wetted wall encloses a chamber (sealed): its volume change is reported
        (:meth:`volume_change`; not for the darcy kind).

    Attributes: ``formulation`` (``displacement`` or ``mixed``), ``model``, ``mech`` (the
    :class:`Mechanics` block), ``ports``, ``kind``, ``order``, ``thickness``.
    """

    def __init__(self, mesh, kind: str, *, params, supports: Supports, ports,
                 springs: tuple = (), order: int | None = None, boundary: str = "pressure",
                 body: Callable | None = None, body_pressure: float | None = None,
                 contact: tuple = (), contact_penalty: float = CONTACT_PENALTY,
                 chamber: bool = True):
        if kind not in KINDS:
            raise ValueError(f"kind must be one of {', '.join(KINDS)}, not {kind!r}")
        if kind == "darcy":
            if body is None or not body_pressure:
                raise ValueError("the darcy kind needs a body force (pressure_body_force) and "
                                 "its inlet pressure body_pressure")
        elif boundary not in mesh.GetBoundaries():
            raise ValueError(f"the part has no '{boundary}' boundary to apply the pressure on")
        if params.model == "auto":
            raise InputError("model: auto is chosen by a run; give the model the run used")
        self.mesh, self.kind, self.params, self.boundary = mesh, kind, params, boundary
        self.ports = (ports,) if isinstance(ports, Port) else tuple(ports)
        if not self.ports or not all(isinstance(p, Port) for p in self.ports):
            raise ValueError("ports: give a Port or a non-empty tuple of Ports")
        regions = [p.region for p in self.ports]
        twice = sorted({r for r in regions if regions.count(r) > 1})
        if twice:
            raise ValueError(f"two output ports on '{twice[0]}': the analysis records every "
                             f"port's value by its region, one port to a region")
        if not all(isinstance(s, Spring) for s in springs):
            raise ValueError("springs: give a tuple of Springs")
        self.model = params.model
        self.order = int(order or params.order or 1)
        self.thickness = float(params.thickness) if mesh.dim == 2 else 1.0
        self._values = solid_fields(mesh)
        self.penal = Parameter(params.penal)
        energy, guard, linear = make_energy(params, self.penal, tuple(self._values))
        self.formulation = formulation_for(params.formulation, model=params.model, nu=params.nu,
                                           plane=params.plane, dim=mesh.dim, order=self.order,
                                           simplices=has_simplices(mesh))
        # the pressure is the block's load factor; the unit pressure carries its sign
        self._unit = Parameter(1.0)
        loads, terms, bodyf = (), None, None
        if kind == "darcy":
            b, scale = body(mesh), 1.0 / float(body_pressure)
            bodyf = lambda u, coeffs: (scale * self._unit) * InnerProduct(b, u)  # noqa: E731
        elif kind == "fixed":
            normal = outward_normal(mesh, boundary)
            loads = (WallPressure(boundary, self._unit, self.thickness, normal),)
        else:
            normal = outward_normal(mesh, boundary)
            terms = follower_terms(boundary, self._unit, self.thickness, normal, mesh.dim)
        self._energy = energy
        self.mech = Mechanics(
            mesh, order=self.order, energy=energy, fields=tuple(self._values),
            supports=supports, loads=loads, body=bodyf,
            springs=tuple(sp for p in self.ports for sp in p.springs()) + tuple(springs),
            thickness=self.thickness, guard=guard,
            linear=linear and kind != "follower" and not contact,
            newton=self._newton(params, contact), residual_terms=terms,
            realcompile=params.newton.compiles(
                linear and kind != "follower" and not contact, mesh.ne * SWEEP_NEWTON
                * element_weight(self.order, mesh.dim, has_simplices(mesh)),
                symbolic=symbolic_tangent(mesh.dim, self.formulation)),
            formulation=self.formulation)
        if contact:
            self.mech.use_contact(SelfContact.on_walls(
                self.mech.space, contact, modulus=params.E1, penalty=contact_penalty,
                reach=CONTACT_REACH, thickness=self.thickness,
                displacement=self.mech.displacement))
        self._chamber = None if kind == "darcy" or not chamber else (
            outward_normal(mesh, boundary),
            held_planes_origin(mesh, (supports.fix_x, supports.fix_y, supports.fix_z)))
        self._forms = self._port_forms()
        self._J = jacobian(Grad(self.mech.u)).Compile()
        self._qpoints = mesh.MapToAllElements(self.mech.rules, VOL)
        xyz = np.array([v.point for v in mesh.vertices], dtype=float)
        self._vertices = mesh(*(xyz[:, i].copy() for i in range(mesh.dim)))

    @staticmethod
    def _newton(params, contact):
        """The run's Newton settings; without contact its load ramp gives up once its
        increment falls below RAMP_FLOOR of the pressure (the path past a pressure maximum
        takes over from the last equilibrium, :mod:`~pacto_ng.post.past_peak`); with contact
        it goes on down to Newton's own least increment (walls whose contact spreads, e.g.
        an arch pressed flat onto the floor under it, take small increments:
        tests/physics/test_contact_path.py)."""
        s = params.newton.settings()
        if contact:
            return s
        return dataclasses.replace(s, min_increment=max(s.min_increment, RAMP_FLOOR))

    @property
    def output_form(self):
        """Δ's functional as a vector on the block's space (``Δ = output_form · x``)."""
        return self._forms[0]

    def solid_values(self) -> tuple:
        """The element fields of the part (all solid: :func:`solid_fields`), as the block's
        ``forward`` takes them."""
        return tuple(self._values.values())

    def energy_density(self, G):
        """The part's strain-energy density ``φ(G)`` per unit reference volume (its materials'
        moduli in place), for stresses by automatic differentiation
        (:func:`~pacto_ng.physics.materials.first_piola_kirchhoff`)."""
        return self._energy(G, self.mech.coeffs)

    def _port_forms(self):
        """``(Δ, [[e_i-component of port k] for k])`` as vectors on the block's space, from
        :meth:`Port.functional`: Δ the sum of the ports' functionals, and per port and axis
        the functional of the unit direction (the value at a point, the mean over an edge or
        a face)."""
        mech, mesh = self.mech, self.mesh
        v = mech.displacement(mech.space.TestFunction())

        def assembled(ports):
            lf = LinearForm(mech.space)
            for p in ports:
                lf += p.functional(mesh, v)
            return lf.Assemble().vec

        axes = np.eye(mesh.dim)
        return assembled(self.ports), [[assembled([Port(p.region, tuple(e))]) for e in axes]
                                       for p in self.ports]

    def _read(self, pressure: float, iterations: int) -> SweepPoint:
        """The converged state's record at ``pressure``."""
        x = self.mech.state_vector
        delta_form, axes = self._forms
        vectors = tuple(tuple(float(f.InnerProduct(x)) for f in forms) for forms in axes)
        along = tuple(float(np.dot(p.direction, vec)) for p, vec in zip(self.ports, vectors))
        u_v = np.asarray(self.mech.u(self._vertices)).reshape(-1, self.mesh.dim)
        contact = ((None,) * 3 if self.mech.contact is None
                   else self.mech.contact.measure(self.mech.u.vec))  # area, force, pressure
        return SweepPoint(pressure, float(delta_form.InnerProduct(x)),
                          float(np.max(np.linalg.norm(u_v, axis=1))),
                          float(np.min(self._J(self._qpoints))), int(iterations), True, 1.0,
                          along, vectors, *contact, volume_change=self.volume_change())

    def volume_change(self) -> float | None:
        """The chamber's volume change at the current state (:func:`~pacto_ng.physics.walls.
        volume_change` of the wetted wall, the origin on the planes held in their normal);
        None for the Darcy kind and where the wall encloses no chamber."""
        if self._chamber is None:
            return None
        normal, origin = self._chamber
        return volume_change(self.mech.u, self.boundary, normal, self.thickness, origin)

    def _failed(self, pressure: float, iterations: int, load_reached: float) -> SweepPoint:
        n = len(self.ports)
        return SweepPoint(float(pressure), np.nan, np.nan, np.nan, int(iterations), False,
                          float(load_reached), (np.nan,) * n,
                          ((np.nan,) * self.mesh.dim,) * n)

    def iteration_seconds(self) -> float:
        """Seconds of one Newton iteration at the current state, measured: the contact's
        pairing (with contact), the tangent's assembly and factorisation and one solve."""
        mech, x = self.mech, self.mech.state_vector
        out = x.CreateVector()
        with compute():
            t0 = time.perf_counter()
            if mech.contact is not None:
                mech.contact.update(mech.a, x)
            mech.assemble_tangent(x, 1.0)
            mech.residual(x, out, 1.0)
            mech.solve_tangent(out, out.CreateVector())
            return time.perf_counter() - t0

    def solve(self, pressure: float) -> SweepPoint:
        """Equilibrium at ``pressure`` (the wall pressure, in the run's units; negative:
        suction), warm-started from the last equilibrium (Newton ramps from zero where that
        fails)."""
        P = float(pressure)
        if not np.isfinite(P):
            raise ValueError(f"pressure must be finite (got {pressure!r})")
        sign = -1.0 if P < 0 else 1.0
        if sign != self._unit.Get():
            self._unit.Set(sign)
            self.mech.load_changed()  # the unit load vector changed sign
        self.mech.target = abs(P)
        try:
            iterations = self.mech.forward_paired(*self.solid_values())
        except NewtonFailure as failure:
            res = failure.result
            return self._failed(P, res.iterations, res.load_reached / abs(P) if P else 0.0)
        # the next pressure's tangents are near this one's (NewtonSettings.sweep)
        self.mech.settings = dataclasses.replace(self.mech.settings, sweep=True)
        return self._read(P, iterations)

    def sweep(self, pressures, *, say: Callable[[str], None] | None = None) -> Sweep:
        """Solve at every pressure in turn, each from the last equilibrium; ``pressures`` in
        increasing order of size.  Where Newton loses the equilibrium on its way to a pressure
        (a chamber that balloons passes a pressure maximum), the path is followed on from the
        last equilibrium with Δ prescribed until the pressure comes back up to it
        (:func:`~pacto_ng.post.past_peak.past_peak`; with contact, paired anew at each of its
        points).  After a failure the remaining pressures are recorded as not converged
        without being attempted (a larger pressure starts from further away).  ``say(line)``, if given,
        gets one progress line per pressure: the pressure, Δ, Newton iterations and
        seconds."""
        pressures = [float(P) for P in pressures]
        if np.any(np.diff(np.abs(pressures)) < 0):
            raise ValueError("pressures: give them in increasing order of size (each pressure "
                             "starts from the last one's equilibrium)")
        out = Sweep(self.kind, [], self)
        failed, last = False, None  # last: the last equilibrium's (pressure, state)
        with compute():
            for P in pressures:
                t0 = time.perf_counter()
                skipped = failed
                pt = self._failed(P, 0, 0.0) if skipped else self.solve(P)
                if not (pt.converged or skipped):
                    pt, peak = past_peak(self, pt, last, say, out.path)
                    out.peak = peak or out.peak
                    if peak and say is not None:
                        say(f"  {self.kind} {self.model}: a pressure maximum "
                            f"{peak['pressure']:.5g} at Δ = {peak['delta']:.5g} on the way")
                failed = not pt.converged
                if not failed:
                    last = (abs(pt.pressure), self.mech.state_vector.FV().NumPy().copy())
                out.points.append(pt)
                out.states.append(self.mech.u.vec.FV().NumPy().copy() if not failed else None)
                if say is not None:
                    say(self._line(pt, time.perf_counter() - t0, skipped))
        return out

    def _line(self, pt: SweepPoint, seconds: float, skipped: bool) -> str:
        head = f"  {self.kind} {self.model} P = {pt.pressure:.4g}: "
        if pt.converged:
            what = f"Δ = {pt.delta:.5g}" + (" (past a pressure maximum)" if pt.past_peak else "")
            if pt.volume_change is not None:
                what += f", chamber ΔV = {pt.volume_change:.4g}"
            if pt.contact_area:
                what += (f", walls in contact over {pt.contact_area:.3g} m² with "
                         f"{pt.contact_force:.3g} N, largest contact pressure "
                         f"{pt.contact_pressure:.3g} Pa")
        elif skipped:
            what = "not attempted (a lower pressure failed)"
        else:
            what = f"not converged (equilibrium up to {100 * pt.load_reached:.3g} % of it)"
        return f"{head}{what}, {pt.iterations} Newton iterations, {seconds:.2f} s"
