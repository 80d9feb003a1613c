"""The mechanics block: (element densities, [pressure]) -> displacement, and its adjoint.

The total potential is

    Π(u) = t ∫ φ(∇u; fields) dΩ + Σ springs - s [ Σ point/edge loads · u + t ∫ b(p) · u dΩ ]

with thickness ``t`` and load factor ``s``.  The dimension is the mesh's: on a 2D mesh ``Ω`` is
the cross-section of a slice of thickness ``t``; on a 3D mesh ``Ω`` is the body and ``t = 1``
(required: the integrals are over the volume).  The residual ``R = ∂Π/∂u`` and the tangent come from
NGSolve's ``Variation`` (automatic differentiation).  Equilibrium is found by
:func:`~pacto_ng.physics.newton.solve_with_continuation`.

Loads that are not the derivative of a potential (follower loads) enter the residual directly:

    R(u) = ∂Π/∂u + t ∫ r(u, v; fields, s) dΩ + (residual_terms),

with ``r`` a *residual density* (linear in the test function ``v``, per unit reference volume)
and ``residual_terms`` a sum of integrals (e.g. on a boundary).  The tangent of either comes
from ``AssembleLinearization`` and is unsymmetric in general; the adjoint then solves
``Kᵀ λ = ∂J/∂u``.

The assembly is chosen from what the energy *declares*
(:class:`~pacto_ng.physics.traits.EnergyTraits`, its ``traits`` attribute; an energy that
declares nothing gets the general route above), never from probes:

* a quadratic energy (``φ = ½ G:C:G``, C per element) in a linear, conservative block: ``K``
  from ``C`` and ``R(u) = K u - s f`` element by element, with a declared numpy modulus
  (``C = E C1``, SIMP) from element matrices from the second design on (from the first after
  :meth:`Mechanics.expect_many_designs`)
  (:class:`~pacto_ng.physics.linear_system.LinearSystem`);
* a field the energy does not read that enters through a body load linear in it (the Darcy
  pressure): the load ``B p`` and ``λᵀ∂R/∂p = -s Bᵀλ`` with a design-independent ``B``
  (:class:`~pacto_ng.physics.body_coupling.BodyCoupling`);
* a stress-free energy with a body load: the load norm from the load vectors.

The declarations that a fast route relies on are verified once when the block is built and a
wrong one raises :class:`~pacto_ng.physics.traits.DeclarationError`.  :attr:`Mechanics.assembly`
says which routes are in use.  The same quadrature rule is pinned in the residual, tangent and
sensitivity forms (see docs: a mismatch gives 1e-2 adjoint errors at order 2).

The block's methods are in three modules: this one builds it (supports, fields, the energy's
forms and the routes; its spaces come from :mod:`~pacto_ng.physics.spaces`),
:class:`~pacto_ng.physics.equilibrium.Equilibrium` solves for equilibrium (the problem Newton
drives, the warm start, the forward pass) and :class:`~pacto_ng.physics.adjoint.Adjoint` runs
the backward pass.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from .adjoint import Adjoint
from .body_coupling import BodyCoupling
from .compiled import compiled, symbolic_linearisation, symbolic_tangent
from .equilibrium import Equilibrium
from .linear_system import LinearSystem
from .mixed import stored_energy
from .newton import NewtonSettings
from .quadrature import integration_rules, mechanics_rules
from .spaces import block_spaces
from .traits import EnergyTraits, traits_of

_UNDECLARED = object()  # a body without the attribute linear_in


@dataclass(frozen=True)
class Supports:
    """Dirichlet conditions by region name (boundaries, named points, and in 3D named edges
    too): ``clamp`` fixes
    every displacement component (as many as the mesh has dimensions), ``fix_x``, ``fix_y``,
    ``fix_z`` one component each (``fix_z``: 3D meshes only)."""

    clamp: tuple[str, ...] = ()
    fix_x: tuple[str, ...] = ()
    fix_y: tuple[str, ...] = ()
    fix_z: tuple[str, ...] = ()

    def names(self) -> tuple[str, ...]:
        """Every region the supports name."""
        return self.clamp + self.fix_x + self.fix_y + self.fix_z

    def per_component(self, dim: int) -> list[tuple[str, ...]]:
        """The regions fixed in each of the ``dim`` displacement components."""
        if dim < 3 and self.fix_z:
            raise ValueError(f"fix_z: the mesh is {dim}D (regions {', '.join(self.fix_z)})")
        return [self.clamp + fix for fix in (self.fix_x, self.fix_y, self.fix_z)[:dim]]


@dataclass
class Field:
    """A coefficient the energy depends on: element-wise (L2-0, numpy input) or a given space."""

    name: str
    space: object = None  # None: L2 order 0 on the mesh
    gf: object = None


class Mechanics(Equilibrium, Adjoint):
    """Finite-strain (or linear) elasticity as a block.

    Parameters
    ----------
    mesh : ngsolve.Mesh
        2D (triangles, quadrilaterals) or 3D (tetrahedra, hexahedra).
    order : int
        Polynomial order of the VectorH1 displacement (1, 2, 3).
    thickness : float
        Out-of-plane thickness ``t`` of a 2D mesh; must be 1 on a 3D mesh.
    energy : callable ``(G, coeffs) -> CF``
        Strain-energy density per unit volume; ``G = ∇u`` and ``coeffs`` maps every field name
        to its GridFunction.  Its ``traits`` attribute
        (:class:`~pacto_ng.physics.traits.EnergyTraits`, e.g. from
        :func:`~pacto_ng.physics.energy.make_energy` or
        :func:`~pacto_ng.physics.traits.declare`) chooses the fast routes; without it the
        general route is used.
    fields : sequence of str or Field
        The block inputs (element-wise densities by default; a :class:`Field` with a space for
        e.g. the pressure).
    body : callable ``(u, coeffs) -> CF`` or None
        Body-force potential density ``b·u`` per unit volume (scaled by the load factor),
        linear in ``u``.  Its attribute ``linear_in`` (a field name, or None) declares the one
        field it reads, linearly (the load vector is then ``B p`` when the energy declares it
        does not read that field too, see
        :class:`~pacto_ng.physics.body_coupling.BodyCoupling`); without the attribute that
        field is the one field on its own space (not element-wise) that the energy declares it
        does not read, if there is exactly one.  Verified when the block is built
        (:class:`~pacto_ng.physics.traits.DeclarationError`); ``linear_in = None`` takes the
        general route.
    guard : callable ``(G, coeffs) -> CF`` or None
        A CF that must stay positive (``det F``), or None: at the points the energy declares
        (:attr:`~pacto_ng.physics.traits.EnergyTraits.guard_points`: the quadrature points,
        or also every element's vertices, edge midpoints and centroid; :attr:`guard_points`).
    linear : bool
        The whole residual (residual density and terms included) is linear in u (one Newton
        step; the tangent does not depend on u).  A residual density may declare the mesh
        dimensions in which it is affine in u (its attribute ``affine_dims``, e.g. the Darcy
        follower load: 2D only); on a mesh of another dimension the block is nonlinear
        (:attr:`linear` False) whatever ``linear`` says.
    residual_terms : callable ``(u, v, load) -> integral`` or None
        Extra residual terms that are not the derivative of a potential (e.g. a follower
        pressure): the returned sum of integrals, linear in the test function ``v``, is *added
        to the residual* ``R(u)``; ``load`` is the load-factor Parameter, which the terms must
        include themselves (and the thickness).  Their tangent comes from
        ``AssembleLinearization``, so it is unsymmetric in general.  They must not depend on
        the block's fields: the backward pass leaves them out of ``∂R/∂ρ`` (use
        ``residual_density`` for volume terms that do).
    residual_density : callable ``(u, v, coeffs, load) -> CF`` or None
        A non-conservative volume term ``r(u, v)`` per unit reference volume, linear in ``v``:
        ``t ∫ r dΩ`` is *added to the residual* (integrated with the block's rule
        :attr:`DX`, multiplied by the thickness here).  ``load`` is the load-factor Parameter,
        which ``r`` must include itself; ``coeffs`` maps field names to GridFunctions and ``r``
        may depend on them: its ``∂R/∂field`` is part of the backward pass.  ``u`` and ``v`` are
        trial/test functions for the residual and tangent, GridFunctions ``(u, λ)`` for the
        sensitivity.  Example: :func:`pacto_ng.physics.darcy_load.darcy_follower`.
    symmetric : bool or None
        Whether the tangent is symmetric; default: neither ``residual_terms`` nor
        ``residual_density`` given.
    realcompile : bool
        Compile the CoefficientFunctions of the Newton forms (energy, residual density) to
        machine code (``Compile(realcompile=True)``: needs NGSolve's ``ngscxx`` and a C++
        compiler; 10-30 s once per form).  Measured on 1710 triangles, P1: Neo-Hookean tangent
        assembly 2.6x, Wang 3.6x faster, the matrix equal to round-off.
    inverse : str or None
        Direct solver of the tangent; default ``sparsecholesky`` for a symmetric tangent and
        ``umfpack`` otherwise.  With an unsymmetric tangent the adjoint solves ``Kᵀ λ = ∂J/∂u``.
    formulation : {"displacement", "mixed"}
        ``mixed``: the displacement with an element dilatation and pressure, condensed out of
        the tangent, against volumetric locking (:mod:`~pacto_ng.physics.mixed`).  The state
        is then ``(u, ϑ, p̃)`` on :attr:`space` (``gfx``; ``gfu`` is its displacement): the
        vectors the block passes to and takes from the responses are states.

    Public state: ``result`` (the :class:`~pacto_ng.physics.newton.NewtonResult` of the last
    forward pass: iterations, load reached, ...; None before), ``u`` (the displacement),
    ``state_vector`` and ``ndof`` (:class:`~pacto_ng.physics.equilibrium.Equilibrium`),
    ``space`` (the unknowns' space), ``lam`` (the adjoint state), :attr:`state` /
    :meth:`set_state` (the warm start: a :class:`~pacto_ng.physics.equilibrium.WarmState`),
    ``adjoint_solves`` / ``adjoint_solves_skipped`` and ``self_adjoint_shortcut`` (set False
    to always solve the adjoint), :attr:`assembly` (the routes in use).  ``gfx``, ``fes``
    and ``gfu`` (the state, the displacement's space and its GridFunction) are the block's
    storage, read within physics/ alone.
    """

    def __init__(self, mesh, *, order: int = 1, energy: Callable, fields=("rho_bar",),
                 supports: Supports = Supports(), loads=(), springs=(), body: Callable | None = None,
                 thickness: float = 1.0, guard: Callable | None = None, linear: bool = False,
                 newton: NewtonSettings = NewtonSettings(), output: str = "u",
                 inverse: str | None = None, intorder: int | None = None,
                 residual_terms: Callable | None = None, symmetric: bool | None = None,
                 residual_density: Callable | None = None, realcompile: bool = False,
                 formulation: str = "displacement"):
        from ngsolve import L2, GridFunction, Parameter, dx

        if order not in (1, 2, 3, 4):
            raise ValueError(f"element order must be 1, 2 or 3 (got {order})")
        if thickness <= 0:
            raise ValueError("thickness must be positive")
        if mesh.dim == 3 and thickness != 1.0:
            raise ValueError(f"thickness must be 1 on a 3D mesh (got {thickness:g}): the "
                             f"integrals are over the volume")
        self.mesh, self.order, self.thickness = mesh, order, float(thickness)
        conservative = residual_terms is None and residual_density is None
        self.symmetric = conservative if symmetric is None else bool(symmetric)
        if inverse is None:
            inverse = "sparsecholesky" if self.symmetric else "umfpack"
        if residual_density is not None and mesh.dim not in getattr(
                residual_density, "affine_dims", (mesh.dim,)):
            linear = False  # e.g. the follower load's cofactor: quadratic in ∇u in 3D
        self.linear, self.settings, self.inverse_type = bool(linear), newton, inverse
        self.realcompile = bool(realcompile)
        self.fields = [f if isinstance(f, Field) else Field(f) for f in fields]
        self.inputs = tuple(f.name for f in self.fields)
        self.output = output
        # the unknowns: the displacement, or (u, ϑ, p̃) (mixed.py)
        kw, self.fes, self.mixed, self.space = block_spaces(mesh, order, supports, formulation)
        self.formulation = formulation
        self.free = np.array(list(self.space.FreeDofs()), dtype=bool)
        self.l2 = L2(mesh, order=0)
        for f in self.fields:
            f.space = f.space or self.l2
            f.gf = GridFunction(f.space)
        self.coeffs = {f.name: f.gf for f in self.fields}
        self.one = GridFunction(self.l2)  # the constant 1: direction of element-wise derivatives
        self.one.vec[:] = 1.0
        self.load = Parameter(1.0)
        self.target = 1.0  # load factor of the next forward pass (continuation over iterations)
        # one rule for every form: degree 1 on order-1 simplices, else 2 (order + bubble)
        self.rules = (integration_rules(intorder) if intorder else
                      mechanics_rules(order, bubble="orderinner" in kw))
        self.DX = dx(intrules=self.rules)
        self._declare(energy, body, residual_density)
        self.loads, self.springs = tuple(loads), tuple(springs)
        self._build_forms(body, residual_terms, residual_density)
        self._start_routes(guard, linear, body, residual_terms)
    def _declare(self, energy, body, residual_density) -> None:
        """The energy, the body load and the residual density, with what the energy declares
        (checked against the block's fields)."""
        self._energy, self._body = energy, body
        self._traits = traits_of(energy)
        reads = self._traits.reads
        if reads is not None and not set(reads) <= set(self.inputs):
            raise ValueError(f"the energy declares it reads {', '.join(reads)}, but the block's "
                             f"fields are {', '.join(self.inputs) or 'none'}")
        # whether the energy reads each field (declared; every field where it declares nothing)
        self._reads = {f.name: reads is None or f.name in reads for f in self.fields}
        self._rdens = residual_density

    def _build_forms(self, body, residual_terms, residual_density) -> None:
        """The state (:attr:`gfx`, :attr:`gfu`), the tangent's form :attr:`a` (the potential's
        variation and the non-conservative terms) and the body load's LinearForm, with its
        coupling ``B p`` where a field enters through it alone."""
        from ngsolve import BilinearForm, GridFunction, LinearForm, Variation

        x = self.space.TrialFunction()
        u, v = self.displacement(x), self.displacement(self.space.TestFunction())
        self.gfx = GridFunction(self.space)  # the state: u, or (u, ϑ, p̃)
        self.gfu = self.displacement(self.gfx)  # the displacement (a view of the state)

        def tangent_form():
            # the mixed formulation's element fields are condensed out of the tangent
            a = BilinearForm(self.space, symmetric=self.symmetric,
                             condense=self.mixed is not None)
            with symbolic_linearisation(symbolic_tangent(self.mesh.dim, self.formulation)):
                a += Variation(self.potential(x))
                if residual_density is not None:
                    a += self.hot(self.residual_density(u, v)) * self.DX
                if residual_terms is not None:
                    a += residual_terms(u, v, self.load)
            return a

        self.a = tangent_form()
        # a second form of the same tangent, for the iterative route's preconditioner of a
        # nonlinear energy (never one with a linear system), assembled at rest once per design
        # (LinearSolver, ``at_rest``); not for the mixed formulation, whose condensed tangent
        # keeps BDDC on each tangent
        nonlinear = not (self.linear or self._traits.quadratic)
        self._tangent_form = tangent_form if nonlinear and self.mixed is None else None
        # the body force is linear in u: its residual is a LinearForm, assembled once per design,
        # not re-evaluated (and differentiated twice) in every Newton iteration (measured: the
        # Darcy body term doubled the cost of AssembleLinearization of a Neo-Hookean form)
        self._fbody = None
        if body is not None:
            self._fbody = LinearForm(self.space)
            self._fbody += (self.thickness * body(v, self.coeffs)).Compile() * self.DX
        self._fbody_stale = True
        # which fields the energy reads (declared); a field that enters only through a body
        # load linear in it (the Darcy pressure) gives the load as B p (BodyCoupling)
        self._coupling = None
        if self._fbody is not None:
            field = self._coupled_field(body)
            if field is not None:
                self._coupling = BodyCoupling.build(self, field, self._fbody)

    def _start_routes(self, guard, linear: bool, body, residual_terms) -> None:
        """The assembly routes (the linear system of a linear, conservative block with a
        quadratic energy; the load norm's) and the equilibrium and adjoint solvers."""
        conservative = self._rdens is None and residual_terms is None
        # a linear, conservative problem: R(u) = K u - s f with K independent of u and s (also
        # with a design-dependent body load: f is then assembled once per design)
        self._lin = None
        if linear and conservative and self._traits.quadratic and self.mixed is None:
            self._lin = LinearSystem(self, self._coupling)
        # the regions of the tangent's boundary terms, whose dofs an iterative solver's BDDC
        # keeps coarse: the springs', or every boundary with residual terms (a follower
        # pressure on a face)
        coarse = None if residual_terms is not None else tuple(sp.where(self.mesh)
                                                               for sp in self.springs)
        self._start_equilibrium(
            guard, coarse=coarse, fixed_loads=body is None and conservative,
            load_vectors=(conservative and body is not None and self._lin is None
                          and self._traits.stress_free))
        self._start_adjoint()

    def _coupled_field(self, body):
        """The field a body load is linear in, alone (see ``body`` in the class docstring), or
        None."""
        declared = getattr(body, "linear_in", _UNDECLARED)
        if declared is None:
            return None
        if declared is not _UNDECLARED:
            for f in self.fields:
                if f.name == declared:
                    # B p is the whole of the field's part of the residual only if the energy
                    # does not read the field too (an undeclared energy may)
                    return None if self._reads[f.name] else f
            raise ValueError(f"body.linear_in: '{declared}' is not a field of the block "
                             f"(fields: {', '.join(self.inputs)})")
        candidates = [f for f in self.fields
                      if f.space is not self.l2 and not self._reads[f.name]]
        return candidates[0] if len(candidates) == 1 else None

    # -- the energy ------------------------------------------------------------------------
    @property
    def energy(self) -> Callable:
        """The strain-energy density ``(G, coeffs) -> CF`` this block was built with."""
        return self._energy

    @property
    def energy_traits(self) -> EnergyTraits:
        """What the energy declares (:class:`~pacto_ng.physics.traits.EnergyTraits`)."""
        return self._traits

    @property
    def guard_points(self) -> str | None:
        """Where the guard is checked: ``"quadrature"`` or ``"element"`` (declared by the
        energy, :class:`~pacto_ng.physics.traits.EnergyTraits`), None without a guard."""
        return None if self._guard is None else self._traits.guard_points

    @property
    def energy_fields(self) -> dict:
        """``{field name: whether the energy reads it}`` (declared; True for every field of an
        energy that declares nothing)."""
        return dict(self._reads)

    @property
    def body(self) -> Callable | None:
        """The body-force potential density ``(u, coeffs) -> CF`` (None: no body load)."""
        return self._body

    @property
    def has_residual_density(self) -> bool:
        """Whether a non-conservative volume term (a follower load) is part of the residual."""
        return self._rdens is not None

    @property
    def linear_system(self) -> LinearSystem | None:
        """The :class:`~pacto_ng.physics.linear_system.LinearSystem` of a linear, conservative
        block with a quadratic energy (None: the general route)."""
        return self._lin

    @property
    def assembly(self) -> dict:
        """The routes in use (read-only description, for tests and the run summary):

        * ``linear_system``: None (``Variation``), ``"hessian"`` (``K`` from ``C`` per element)
          or ``"element_matrices"`` (``K`` from element matrices, from the second design on,
          or the first after :meth:`expect_many_designs`);
        * ``modulus``: ``"numpy"`` when ``E`` per design comes from the declared numpy modulus;
        * ``body_coupling``: the fields whose body load is ``B p``;
        * ``load_norm``: ``"linear_system"``, ``"load_vectors"`` (stress-free energy: the norm
          of point and body loads), ``"fixed"`` (design-independent loads: computed once) or
          ``"residual"`` (the residual at ``u = 0``).
        """
        lin = self._lin
        return {"linear_system": None if lin is None else lin.route,
                "modulus": "numpy" if lin is not None and lin.uses_modulus else None,
                "body_coupling": () if self._coupling is None else (self._coupling.field.name,),
                "load_norm": self.load_norm_route}

    def expect_many_designs(self):
        """Say that many designs follow (an optimisation): a linear system builds its element
        matrices at the next design, not at the second
        (:meth:`~pacto_ng.physics.linear_system.LinearSystem.expect_many_designs`)."""
        if self._lin is not None:
            self._lin.expect_many_designs()

    def hot(self, cf):
        """``cf`` compiled for a form that Newton assembles in every iteration
        (:func:`~pacto_ng.physics.compiled.compiled`, to machine code with :attr:`realcompile`)."""
        cf, self.realcompile = compiled(cf, self.realcompile)
        return cf

    def displacement(self, x):
        """The displacement of a state ``x`` (a trial or test function or a GridFunction of
        :attr:`space`): ``x`` itself, or its first component in the mixed formulation."""
        return x if self.mixed is None else self.mixed.split(x)[0]

    def components(self, x) -> tuple:
        """Every component of a state ``x``: ``(u,)``, or ``(u, ϑ, p̃)`` (mixed)."""
        return (x,) if self.mixed is None else self.mixed.split(x)

    def stored_density(self, x, coeffs=None):
        """The stored energy density ``t φ`` of a state ``x`` (per unit area in 2D): ``φ(∇u)``,
        or ``φ(F̄ - I) + p̃ (J - Θ)`` in the mixed formulation (:mod:`~pacto_ng.physics.mixed`;
        ``J = Θ`` at equilibrium, in the element mean)."""
        coeffs = self.coeffs if coeffs is None else coeffs
        return self.thickness * stored_energy(self._energy, self.mixed, self.components(x),
                                              coeffs)

    def volume_density(self, x, coeffs=None):
        """Everything integrated over the volume: ``t (φ - s b·u)`` (a CF, per unit area) of a
        state ``x``; ``coeffs`` replaces the fields (default: the block's GridFunctions)."""
        coeffs = self.coeffs if coeffs is None else coeffs
        dens = self.stored_density(x, coeffs)
        if self._body is not None:
            dens = dens - self.load * self.thickness * self._body(self.displacement(x), coeffs)
        return dens

    def residual_density(self, u, v, coeffs=None):
        """The non-conservative volume term ``t r(u, v; fields, s)`` (a CF, per unit area) of
        the displacements ``u`` and ``v``."""
        return self.thickness * self._rdens(u, v, self.coeffs if coeffs is None else coeffs,
                                            self.load)

    def potential(self, x):
        """Π(x) as a sum of integrals, without the body-force work (:meth:`residual` subtracts
        ``s t ∫ b·v dΩ``, a LinearForm)."""
        # compiled CFs assemble 2-3x faster (measured: 0.45 -> 0.24 s for 19k quads)
        u = self.displacement(x)
        total = self.hot(self.stored_density(x)) * self.DX
        for ld in self.loads:
            total = total + ld.work(self.mesh, u, scale=-1.0 * self.load)
        for sp in self.springs:
            total = total + sp.energy(self.mesh, u)
        return total
