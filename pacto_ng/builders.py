"""The builders of an optimisation chain, one concern each, and the chain a case calls them in.

A case's ``chain(b)`` (``Case.chain``; :func:`standard_chain` unless the case writes its own)
gets a :class:`Builder` ``b`` -- the case, its parameters, its meshed geometry and its set-up
-- and calls the builders in order::

    design   = b.design()                           x -> ρ -> ρ̃ -> ρ̄ (per field)
    model    = b.energy(design)                     φ(∇u; ρ̄) of --model
    pressure = b.pressure(model, design)            ρ̄ -> p and its load (none without one)
    mech     = b.mechanics(model, design, pressure) (ρ̄, p) -> u
    response = b.responses(mech, pressure)          u -> the objective of the set-up
    volume   = b.volume(design)                     ρ̄ -> V/V* - 1
    return b.problem(design, pressure, mech, response, volume)

Each builder returns the blocks it adds (with what the next one needs).  A case that needs
another objective writes its own chain and its own response block (any object with ``inputs``,
``output``, ``forward`` and ``backward``, :mod:`pacto_ng.core`) in place of ``b.responses``;
``pacto check-gradients`` then checks its gradient like any other.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from . import responses as R
from .core import Chain
from .design import DesignField, Embed, FixPassive, near_boundary
from .errors import InputError
from .filters import ConeFilter, HeavisideProjection, HelmholtzFilter, IdentityFilter
from .parallel import bounding_box
from .physics import darcy_load
from .physics.compiled import NEWTON_PER_ITERATION, element_weight, symbolic_tangent
from .physics.darcy_leakage import Outflow
from .physics.energy import make_energy
from .physics.loads import PointLoad
from .physics.mechanics import Mechanics
from .physics.mixed import formulation_for, has_simplices
from .problem import Problem
from .settings import Settings, setting
from .setup import OBJECTIVES, Pressure


@dataclass(frozen=True)
class DesignSettings(Settings):
    """The design field: volume limits, filter, projection threshold and the start design."""

    volfrac: float = setting(0.2, "", "allowed volume fraction of the design domain",
                             range="(0, 1)")
    volfrac2: float = setting(0.0, "", "volume fraction limit of the stiff material (0: none)",
                              range="[0, 1)")
    filter: str = setting("helmholtz", "", "helmholtz | cone | none",
                          choices=("helmholtz", "cone", "none"))
    filter_radius: float = setting(0.0, "m", "filter radius R (0: 3 mesh sizes)",
                                   range="[0, inf)")
    eta: float = setting(0.5, "", "projection threshold η", range="(0, 1)")
    inlet_wall: float = setting(0.0, "m", "thickness of the passive solid wall kept around a "
                                "pressure inlet, so that its chamber stays sealed (0: none)",
                                range="[0, inf)")
    seed_density: float = setting(0.0, "", "initial design density (0: volfrac)",
                                  range="[0, 1]")
    init_design: str = setting("", "", "start from the design x of this run folder (its "
                               "checkpoint.npz; the same case and mesh), e.g. a run at a "
                               "lower load")

    def check(self):
        if 0 < self.volfrac2 < 1e-6:
            raise InputError(f"volfrac2: {self.volfrac2:g} leaves no stiff material (0: no limit "
                             "on it)")
        if self.volfrac2 > self.volfrac:
            raise InputError(f"volfrac2: the stiff material's fraction must not exceed volfrac "
                             f"(got {self.volfrac2:g} > {self.volfrac:g})")


@dataclass(frozen=True)
class ObjectiveSettings(Settings):
    """Which objective the case's set-up is optimised for, and its limits."""

    objective: str = setting("", "", "case objective variant (empty: the case's default)",
                             choices=("",) + OBJECTIVES)
    se_max: float = setting(0.0, "J", "strain-energy limit of objective output_se (0: the "
                            "case's default)", range="[0, inf)")
    leak_max: float = setting(0.0, "", "limit on the Darcy outflow through the zero-pressure "
                              "boundaries, Q/(Kv P_in) (0: none; a closed chamber ~1e-5, a "
                              "leak 1e-2 and up)", range="[0, inf)")


@dataclass
class DesignChain:
    """Design variables to physical densities: the field, its blocks, the projections (whose
    β the schedule sets), the SIMP penalty (an NGSolve Parameter) and the names of the
    physical density field(s)."""

    field: object
    blocks: list
    projections: list
    penal: object
    names: tuple[str, ...]


@dataclass
class PressureLoad:
    """The Darcy pressure block and how its load enters the mechanics: a body force (fixed)
    or a residual density (follower); all None for a case without pressure."""

    block: object = None
    field: object = None
    body: object = None
    follower: object = None

    @property
    def blocks(self) -> list:
        return [] if self.block is None else [self.block]


@dataclass
class Responses:
    """The response blocks, the objective's name, the responses reported each iteration and
    the extra constraints (beyond the volume)."""

    blocks: list
    objective: str
    reports: list = field(default_factory=list)
    constraints: list = field(default_factory=list)


@dataclass
class Model:
    """The energy of ``--model`` on the design's densities, its Newton guard and whether it is
    linear (one linear solve per design)."""

    energy: object
    guard: object
    linear: bool


class Builder:
    """What a case's chain is built from: the case, its parameters, the meshed geometry
    (:class:`~pacto_ng.mesh.Meshed`: ``mesh``, ``h``, ``shape``) and the set-up; its
    methods are the builders, called in order by the case's ``chain``."""

    def __init__(self, case, params, meshed, setup):
        self.case, self.params, self.meshed, self.setup = case, params, meshed, setup

    @property
    def mesh(self):
        """The ``ngsolve.Mesh``."""
        return self.meshed.mesh

    def design(self) -> DesignChain:
        """Embed, filter (Helmholtz, cone or none), project and fix the passive elements, for
        one or two design fields (``setup.materials``)."""
        from ngsolve import Parameter

        mesh, setup, params = self.mesh, self.setup, self.params
        try:
            wall = None
            if params.inlet_wall > 0:
                if setup.pressure is None:
                    raise ValueError(f"inlet_wall: case '{self.case.name}' has no pressure inlet")
                wall = near_boundary(mesh, setup.pressure.inlet, params.inlet_wall)
            field_ = DesignField(mesh, solid=setup.solid, void=setup.void, wall=wall)
        except ValueError as err:
            raise InputError(str(err)) from None
        radius = params.filter_radius or 3.0 * self.meshed.h
        lo, hi = bounding_box(mesh)
        diameter = float(np.linalg.norm(hi - lo))
        if radius > diameter:
            raise InputError(f"filter_radius: {radius:g} is larger than the domain ({diameter:g} "
                             "across): the filter would average the whole design")
        nf = setup.materials
        names = ("rho_bar",) if nf == 1 else ("rho_bar1", "rho_bar2")
        blocks, projections = [], []
        if nf == 2:
            blocks += [Slice(field_.n, 0, "x1"), Slice(field_.n, 1, "x2")]
        for i, out in enumerate(names):
            suf = "" if nf == 1 else str(i + 1)
            xin = "x" if nf == 1 else f"x{suf}"
            blocks.append(Embed(field_, inputs=(xin,), output=f"rho{suf}"))
            if params.filter == "helmholtz":
                flt = HelmholtzFilter(mesh, radius, inputs=(f"rho{suf}",),
                                      output=f"rho_tilde{suf}", solver=params.solver)
            elif params.filter == "cone":
                flt = ConeFilter(field_.centroids(), field_.areas, radius, inputs=(f"rho{suf}",),
                                 output=f"rho_tilde{suf}")
            else:
                flt = IdentityFilter(inputs=(f"rho{suf}",), output=f"rho_tilde{suf}")
            blocks.append(flt)
            pr = HeavisideProjection(params.beta, params.eta, inputs=(f"rho_tilde{suf}",),
                                     output=f"rho_proj{suf}")
            projections.append(pr)
            blocks.append(pr)
            blocks.append(FixPassive(field_, inputs=(f"rho_proj{suf}",), output=out))
        return DesignChain(field_, blocks, projections, Parameter(params.penal), names)

    def energy(self, design: DesignChain) -> Model:
        """The energy of ``--model`` (:mod:`pacto_ng.physics.energy`) with SIMP on the
        design's densities."""
        return Model(*make_energy(self.params, design.penal, design.names))

    def pressure(self, model: Model, design: DesignChain, suffix: str = "") -> PressureLoad:
        """The Darcy pressure of the set-up's inlet and zero-pressure boundaries, and its load:
        fixed (a body force) or follower (a residual density, docs/theory.md §4); empty for a
        set-up without pressure.  ``suffix`` names its output ``p`` + suffix (several
        realisations of the design in one chain, :mod:`pacto_ng.robust`)."""
        params, setup, name = self.params, self.setup, self.case.name
        if params.load_type == "follower" and setup.pressure is None:
            raise InputError(f"load_type: case '{name}' has no pressure load to follow the "
                             "deformation")
        if params.inlet and setup.pressure is None:
            raise InputError(f"inlet: case '{name}' has no pressure load")
        if setup.pressure is None:
            return PressureLoad()
        h = self.meshed.h
        if params.delta_s < 0.1 * h:
            raise InputError(f"delta_s: {params.delta_s:g} is below a tenth of the element size "
                             f"{h:g} (set delta_s in the units of the mesh)")
        if not abs(params.p_out) < params.load:
            raise InputError(f"p_out: the outside pressure {params.p_out:g} must be smaller in "
                             f"size than the inlet pressure (load {params.load:g})")
        pressure = setup.pressure
        if params.inlet:
            pressure = Pressure(inlet=tuple(params.inlet.split("|")), zero=pressure.zero)
        try:
            # Wang: the follower load sees the deformation I + γ∇u of the energy's large-strain
            # part (void: the fixed load), unless follower_wang=0
            gamma = model.energy.gamma if params.model == "wang" and params.follower_wang else None
            block, pfield, body = darcy_load.for_case(self.mesh, params.darcy, params.load,
                                                      pressure, design.names[0],
                                                      order=params.order, output="p" + suffix,
                                                      gamma=gamma, solver=params.solver)
        except ValueError as err:
            raise InputError(str(err)) from None
        if params.load_type == "follower":
            # -cof(F)∇p: a residual term (unsymmetric tangent, transposed adjoint).  It is affine
            # in u in 2D, so a linear material keeps its one-step linear solve.
            return PressureLoad(block, pfield, None, body)
        return PressureLoad(block, pfield, body, None)

    def mechanics(self, model: Model, design: DesignChain, pressure: PressureLoad,
                  suffix: str = ""):
        """The mechanics block ``(ρ̄, [p]) -> u`` (``u`` + ``suffix``) with the set-up's
        supports, loads and springs."""
        params, setup = self.params, self.setup
        fields = list(design.names) + ([pressure.field] if pressure.field is not None else [])
        loads = tuple(PointLoad(ld.region, tuple(params.load * np.asarray(ld.force)))
                      for ld in setup.loads)
        # a 2D mesh is a slice of thickness t; a 3D mesh is the body itself
        thickness = params.thickness if self.mesh.dim == 2 else 1.0
        formulation = self.formulation()
        try:
            return Mechanics(self.mesh, order=params.order, energy=model.energy, fields=fields,
                             supports=setup.supports, loads=loads, springs=setup.all_springs,
                             body=pressure.body, thickness=thickness, guard=model.guard,
                             linear=model.linear, newton=params.newton.settings(),
                             residual_density=pressure.follower,
                             realcompile=params.newton.compiles(
                                 model.linear, self.mesh.ne * params.iterations
                                 * NEWTON_PER_ITERATION * element_weight(
                                     params.order, self.mesh.dim, has_simplices(self.mesh)),
                                 symbolic=symbolic_tangent(self.mesh.dim, formulation)),
                             output="u" + suffix, formulation=formulation)
        except ValueError as err:
            raise InputError(str(err)) from None

    def formulation(self) -> str:
        """``displacement`` or ``mixed`` (``--set formulation``, :mod:`pacto_ng.physics.mixed`)
        for this model, material, plane, order and mesh."""
        params, mesh = self.params, self.mesh
        return formulation_for(params.formulation, model=params.model, nu=params.nu,
                               plane=params.plane, dim=mesh.dim, order=params.order,
                               simplices=has_simplices(mesh))

    def responses(self, mech, pressure: PressureLoad, suffix: str = "") -> Responses:
        """The blocks of the set-up's objective (or ``--set objective``): compliance, strain
        energy, or an output displacement (alone, over the strain energy, or under a
        strain-energy limit); and, with ``leak_max`` > 0, the limit on the Darcy outflow
        (:class:`~pacto_ng.physics.darcy_leakage.Outflow`).  ``suffix`` is appended to the
        name of every value they make."""
        resp = self._objective(mech, pressure, suffix)
        if self.params.leak_max > 0:
            if pressure.block is None:
                raise InputError(f"leak_max: case '{self.case.name}' has no pressure load")
            try:
                outflow = Outflow(pressure.block, output="leak" + suffix)
            except ValueError as err:
                raise InputError(str(err)) from None
            resp.blocks += [outflow, Bound(self.params.leak_max, (outflow.output,),
                                           "leak_limit" + suffix)]
            resp.reports.append(outflow.output)
            resp.constraints.append("leak_limit" + suffix)
        return resp

    def _objective(self, mech, pressure: PressureLoad, suffix: str) -> Responses:
        params, setup = self.params, self.setup
        obj = params.objective or setup.objective
        if obj not in OBJECTIVES:
            raise InputError(f"objective: must be one of {', '.join(OBJECTIVES)} (got '{obj}')")
        n = {k: k + suffix for k in ("compliance", "se", "delta", "objective", "se_limit")}
        if obj == "compliance":
            if pressure.follower is not None:
                raise InputError("objective: compliance is not defined for a follower load (the "
                                 "load vector depends on u); use energy, mechanism, output or "
                                 "output_se")
            if pressure.body is not None:
                return Responses([darcy_load.Compliance(mech, pressure.block,
                                                        output=n["compliance"])], n["compliance"])
            return Responses([R.compliance(mech, output=n["compliance"])], n["compliance"])
        if obj == "energy":
            return Responses([R.StrainEnergy(mech, output=n["se"])], n["se"])
        if not setup.ports:
            raise InputError(f"objective '{obj}' needs an output port")
        blocks = [R.output_displacement(mech, setup.output, output=n["delta"])]
        # several ports (a gripper's jaws): each one's own d·u reported too (history.csv
        # delta_<region>: whether both close, or one swings while the other stays)
        ports = [R.output_displacement(mech, port, output=f"delta_{port.region}{suffix}")
                 for port in setup.ports] if len(setup.ports) > 1 else []
        each = [b.output for b in ports]
        blocks += ports
        if obj == "output":
            return Responses(blocks + [R.Scale(-1.0, (n["delta"],), n["objective"])],
                             n["objective"], [n["delta"]] + each)
        if obj == "output_se":  # max Δ subject to SE <= se_max
            se_max = params.se_max or setup.se_max
            if not se_max > 0:
                raise InputError(f"se_max: objective output_se needs a positive limit (case "
                                 f"'{self.case.name}' has no default; --set se_max=...)")
            blocks += [R.Scale(-1.0, (n["delta"],), n["objective"]),
                       R.StrainEnergy(mech, output=n["se"]),
                       Bound(se_max, (n["se"],), n["se_limit"])]
            return Responses(blocks, n["objective"], [n["delta"], n["se"]] + each,
                             [n["se_limit"]])
        blocks += [R.StrainEnergy(mech, output=n["se"]),
                   R.MechanismRatio(inputs=(n["delta"], n["se"]), output=n["objective"])]
        return Responses(blocks, n["objective"], [n["delta"], n["se"]] + each)

    def volume(self, design: DesignChain) -> Responses:
        """``V(ρ̄)/V* - 1 <= 0`` on the (total) solid, and on the stiff material where
        ``volfrac2`` > 0 (two materials)."""
        blocks, names = [], []
        for i, out in enumerate(design.names):
            vf = self.params.volfrac if i == 0 else self.params.volfrac2
            if i == 0 or self.params.volfrac2 > 0:
                name = "volume" if i == 0 else "volume2"
                blocks.append(R.Volume(design.field, vf, inputs=(out,), output=name))
                names.append(name)
        return Responses(blocks, "volume", [], names)

    def problem(self, design: DesignChain, pressure: PressureLoad, mech, response: Responses,
                volume: Responses):
        """The :class:`~pacto_ng.problem.Problem`: the chain of the blocks in this order, the
        response's objective, the volume's and the response's constraints."""
        chain = Chain(design.blocks + pressure.blocks + [mech] + response.blocks
                      + volume.blocks, inputs=("x",))
        return Problem(self.case, self.params, self.mesh, design.field, chain,
                       response.objective, volume.constraints + response.constraints, mech,
                       design.projections, design.penal, self.setup, self.meshed.h,
                       response.reports, pressure.block, self.setup.materials,
                       shape=self.meshed.shape)


def standard_chain(b: Builder):
    """The chain of every built-in case: design, energy, [pressure], mechanics, the set-up's
    objective and the volume constraint."""
    design = b.design()
    model = b.energy(design)
    pressure = b.pressure(model, design)
    mech = b.mechanics(model, design, pressure)
    return b.problem(design, pressure, mech, b.responses(mech, pressure), b.volume(design))


class Bound:
    """Block ``a -> a / bound - 1`` (a constraint ``a <= bound`` in the form ``g <= 0``)."""

    def __init__(self, bound, inputs, output):
        self.bound, self.inputs, self.output = float(bound), tuple(inputs), output

    def forward(self, a):
        return float(a) / self.bound - 1.0

    def backward(self, g):
        return (g / self.bound,)


class Slice:
    """Block ``x -> x_i``: the i-th of several stacked design fields of n variables each."""

    def __init__(self, n, i, output):
        self.n, self.i = n, i
        self.inputs, self.output = ("x",), output

    def forward(self, x):
        return np.asarray(x)[self.i * self.n:(self.i + 1) * self.n].copy()

    def backward(self, g):
        full = np.zeros(2 * self.n)
        full[self.i * self.n:(self.i + 1) * self.n] = g
        return (full,)
